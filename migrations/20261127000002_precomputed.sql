-- What a replica precomputed for a registered scenario (its statistics and
-- indexes, `Planner::encode_precomputed`), compressed with zstd and cut in
-- chunks, so that another replica loads it instead of computing it again.
-- `format` is the encoding's version: a row of another is recomputed, as is
-- one that does not decode. The header and its chunks are written in one
-- transaction, so a replica killed while writing leaves no half row, and
-- they go with their scenario.
CREATE TABLE precomputed (
    scenario_id text        PRIMARY KEY REFERENCES scenarios (id) ON DELETE CASCADE,
    format      integer     NOT NULL,
    raw_bytes   bigint      NOT NULL,
    chunks      integer     NOT NULL,
    created_at  timestamptz NOT NULL DEFAULT now()
);

CREATE TABLE precomputed_chunks (
    scenario_id text    NOT NULL REFERENCES precomputed (scenario_id) ON DELETE CASCADE,
    n           integer NOT NULL,
    data        bytea   NOT NULL,
    PRIMARY KEY (scenario_id, n)
);

-- The chunks are compressed already: PostgreSQL need not try again.
ALTER TABLE precomputed_chunks ALTER COLUMN data SET STORAGE EXTERNAL;
