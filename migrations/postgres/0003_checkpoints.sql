-- The last checkpoint of a running job (its complete state, `--checkpoint-s`) and the
-- byte length of each of its CSV files at that step, as JSON: a worker that claims the
-- job again resumes from it, and the rows uploaded after it are dropped.
CREATE TABLE job_checkpoints (
    job_id TEXT PRIMARY KEY REFERENCES jobs (id) ON DELETE CASCADE,
    simulated_time DOUBLE PRECISION NOT NULL,
    step BIGINT NOT NULL,
    series_lengths TEXT NOT NULL,
    data BYTEA NOT NULL
);
-- The simulated time the current attempt started from (NULL: from t = 0).
ALTER TABLE jobs ADD COLUMN resumed_from DOUBLE PRECISION;
-- Claims a worker's shutdown gave back: they fence writes like every claim, but only
-- attempts - releases counts against max_attempts.
ALTER TABLE jobs ADD COLUMN releases BIGINT NOT NULL DEFAULT 0;
