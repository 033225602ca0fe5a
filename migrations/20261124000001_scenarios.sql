-- Registered scenarios, shared by every replica pointed at this database.
-- Statistics are never stored: each replica precomputes a scenario on first
-- use. The id is derived from the canonical spec (`s-` and 16 hex digits),
-- so the same spec registered through two replicas at once gives one row.
CREATE TABLE scenarios (
    id         text        PRIMARY KEY,
    format     integer     NOT NULL,
    spec       jsonb       NOT NULL,
    created_at timestamptz NOT NULL DEFAULT now()
);

-- Every replica listens on `vigil_scenarios` and drops a deleted scenario
-- from its cache; the trigger covers deletions made by hand too.
CREATE FUNCTION vigil_scenario_deleted() RETURNS trigger
LANGUAGE plpgsql AS $$
BEGIN
    PERFORM pg_notify('vigil_scenarios', OLD.id);
    RETURN OLD;
END;
$$;

CREATE TRIGGER scenarios_deleted
    AFTER DELETE ON scenarios
    FOR EACH ROW EXECUTE FUNCTION vigil_scenario_deleted();
