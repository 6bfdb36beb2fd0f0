-- The simulated time the current attempt started from (NULL: from t = 0). The embedded
-- store runs its jobs in the serving process and never resumes one: always NULL.
ALTER TABLE jobs ADD COLUMN resumed_from REAL;
