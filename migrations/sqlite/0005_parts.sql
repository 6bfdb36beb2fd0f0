-- A job submitted with ?uncertainty=true queues the coarser parts of its ladder as rows
-- of their own, claimed by whichever workers are free: `parent` names the job, `part`
-- the part's index in the ladder. Parts are never listed; they go with their job.
-- The job's own row runs the user's level, and its `part` counts the parts ended.
ALTER TABLE jobs ADD COLUMN parent TEXT REFERENCES jobs (id) ON DELETE CASCADE;
CREATE INDEX jobs_by_parent ON jobs (parent);
