-- The job table is the queue: a worker claims the oldest queued job, or a running one
-- whose lease expired, with FOR UPDATE SKIP LOCKED, and renews `lease_until` while it
-- runs. `attempts` counts claims and fences every write of the worker holding a claim.
CREATE TABLE jobs (
    seq BIGSERIAL PRIMARY KEY,
    id TEXT NOT NULL UNIQUE,
    name TEXT NOT NULL,
    status TEXT NOT NULL,
    case_json TEXT NOT NULL,
    created_at TEXT NOT NULL,
    started_at TEXT,
    finished_at TEXT,
    step BIGINT NOT NULL DEFAULT 0,
    simulated_time DOUBLE PRECISION NOT NULL DEFAULT 0,
    end_time DOUBLE PRECISION NOT NULL,
    particles BIGINT,
    reason TEXT,
    summary TEXT,
    attempts BIGINT NOT NULL DEFAULT 0,
    worker TEXT,
    run_dir TEXT,
    lease_until TIMESTAMPTZ,
    cancel_requested BOOLEAN NOT NULL DEFAULT FALSE
);
CREATE INDEX jobs_by_status ON jobs (status, seq);

-- The run's CSV files (loads, bodies, probes), appended in chunks of complete lines as
-- the worker writes them, so that every API node serves them, also while the job runs.
CREATE TABLE job_series (
    job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    file TEXT NOT NULL,
    byte_offset BIGINT NOT NULL,
    data BYTEA NOT NULL,
    PRIMARY KEY (job_id, file, byte_offset)
);
