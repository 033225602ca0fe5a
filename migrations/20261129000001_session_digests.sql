-- The request digest of a session's last step (its body's SHA-256), so
-- that a step sent with that step's Idempotency-Key but another body is
-- refused (422) instead of answered with the last step's answer. A
-- replica older than this migration stores steps without touching these
-- columns, so `digest_key` names the key the digest was stored with: a
-- digest counts only while it is `last_key`.
ALTER TABLE sessions ADD COLUMN last_digest bytea;
ALTER TABLE sessions ADD COLUMN digest_key text;
