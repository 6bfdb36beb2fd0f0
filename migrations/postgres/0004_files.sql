-- A job's snapshot files (snapshots/run.pvd and its .vtu files, gzip-compressed), uploaded
-- by its worker as they are written, so that every API node draws the flow after the
-- worker's run directory is gone.
CREATE TABLE job_files (
    job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    name TEXT NOT NULL,
    data BYTEA NOT NULL,
    PRIMARY KEY (job_id, name)
);
