-- Sessions (`/v1/sessions`), shared by every replica pointed at this
-- database: any replica serves any session, and a session outlives the
-- replica that created it. `state` is the session's snapshot (CBOR, in the
-- encoding `format` names); `spec` its scenario's spec (CBOR), so a replica
-- that never saw an inline scenario can rebuild it. `version` counts the
-- steps stored: a step is stored only over the version it was made from.
-- `last_key` and `last_response` are the last step's Idempotency-Key and
-- its answer, replayed to a retry.
CREATE TABLE sessions (
    id            text        PRIMARY KEY,
    scenario_id   text        NOT NULL,
    spec          bytea       NOT NULL,
    format        integer     NOT NULL,
    state         bytea       NOT NULL,
    version       bigint      NOT NULL DEFAULT 0,
    last_key      text,
    last_response bytea,
    created_at    timestamptz NOT NULL DEFAULT now(),
    last_used     timestamptz NOT NULL DEFAULT now()
);

-- Expiry and eviction visit the least recently used first.
CREATE INDEX sessions_last_used ON sessions (last_used);
