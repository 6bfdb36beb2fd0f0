-- A job submitted with ?uncertainty=true runs the resolution ladder (mpsfsi run --uncertainty).
ALTER TABLE jobs ADD COLUMN uncertainty INTEGER NOT NULL DEFAULT 0;
