-- The job table, which is also the queue. IF NOT EXISTS: databases created before
-- migrations were tracked already have it.
CREATE TABLE IF NOT EXISTS jobs (
    seq INTEGER PRIMARY KEY AUTOINCREMENT,
    id TEXT NOT NULL UNIQUE,
    name TEXT NOT NULL,
    status TEXT NOT NULL,
    case_json TEXT NOT NULL,
    created_at TEXT NOT NULL,
    started_at TEXT,
    finished_at TEXT,
    step INTEGER NOT NULL DEFAULT 0,
    simulated_time REAL NOT NULL DEFAULT 0,
    end_time REAL NOT NULL,
    particles INTEGER,
    reason TEXT,
    summary TEXT
);
CREATE INDEX IF NOT EXISTS jobs_by_status ON jobs (status, seq);
