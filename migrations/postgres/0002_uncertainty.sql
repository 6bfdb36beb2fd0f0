-- A job submitted with ?uncertainty=true runs the resolution ladder (mpsfsi run --uncertainty).
ALTER TABLE jobs ADD COLUMN uncertainty BOOLEAN NOT NULL DEFAULT FALSE;
