-- A job submitted with ?uncertainty=true runs the resolution ladder (mpsfsi run --uncertainty).
ALTER TABLE jobs ADD COLUMN uncertainty BOOLEAN NOT NULL DEFAULT FALSE;
-- Its levels run as parts, one after another: `part` (from 0) of `parts` is running.
ALTER TABLE jobs ADD COLUMN part BIGINT NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN parts BIGINT NOT NULL DEFAULT 1;
