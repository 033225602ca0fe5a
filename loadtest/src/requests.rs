//! The plan requests a run replays: generated from `vigil-sim` states
//! ([`Workload`]), or read from a file of bodies.
//!
//! A file of bodies is either a JSON array of plan request bodies or JSON
//! lines (one body per line; blank lines are skipped). [`save`] writes JSON
//! lines when the file name ends in `.jsonl` or `.ndjson`, an array
//! otherwise.

use std::fs;
use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result, bail};
use bytes::Bytes;
use vigil::limits::{MAX_HISTORY_STEPS, MAX_HORIZON, MAX_SENSORS};
use vigil::planner::{PlanRequest, Planner};
use vigil::scenario::{Scenario, builtins};

use vigil_sim::driver::{fleet_size, fleet_types};

use crate::workload::{SessionWorkload, Workload};

/// The planner of the built-in scenario `id` (its statistics computed now,
/// a few milliseconds).
///
/// # Errors
/// If no built-in scenario has that id.
pub fn planner_for(id: &str) -> Result<Planner> {
    let all = builtins();
    let ids: Vec<String> = all.iter().map(|s| s.id.clone()).collect();
    match all.into_iter().find(|s| s.id == id) {
        Some(s) => Ok(Planner::new(s)),
        None => bail!(
            "unknown scenario {id:?}: requests are generated for a built-in scenario ({})",
            ids.join(", ")
        ),
    }
}

/// Who plans: every sensor of type `default`, or a fleet of the scenario's
/// types such as `drone:4,robot:6` (the first four drones, the next six
/// robots).
#[derive(Debug, Clone, Copy, Default)]
pub enum Fleet<'a> {
    /// `workload.sensors` sensors of type `default`.
    #[default]
    Default,
    /// `NAME:COUNT,…`: its sensors replace `workload.sensors`.
    Typed(&'a str),
}

impl Fleet<'_> {
    /// The sensors' types on `planner`'s scenario, one per sensor.
    fn types(self, planner: &Planner, workload: &Workload) -> Result<Vec<usize>> {
        match self {
            Fleet::Default => Ok(vec![0; workload.sensors]),
            Fleet::Typed(fleet) => {
                let n = fleet_size(fleet)
                    .with_context(|| format!("--fleet {fleet:?}: expected NAME:COUNT,…"))?;
                let types = fleet_types(&planner.scenario, Some(fleet), n)
                    .map_err(|e| anyhow::anyhow!("--fleet: {e}"))?;
                check(
                    &Workload {
                        sensors: n,
                        ..workload.clone()
                    },
                    1,
                )?;
                Ok(types)
            }
        }
    }
}

/// The planner of the built-in scenario `id` with `rays_per_pi` set in its
/// spec when given (a scenario of its own id then).
///
/// # Errors
/// If no built-in scenario has that id, or the rays per π are out of
/// bounds.
pub fn planner_with(id: &str, rays_per_pi: Option<u32>) -> Result<Planner> {
    let planner = planner_for(id)?;
    let Some(rays) = rays_per_pi else {
        return Ok(planner);
    };
    let mut spec = planner.scenario.spec.clone();
    spec.rays_per_pi = Some((rays as usize).into());
    let scenario = Scenario::new(spec).map_err(|e| anyhow::anyhow!("--rays-per-pi: {e}"))?;
    Ok(Planner::new(scenario))
}

/// `count` distinct requests of `workload` on `planner`'s scenario, by
/// `fleet`.
///
/// # Errors
/// If the workload is outside the API's bounds (sensors 1..=256, history
/// ≤ 32, horizon 1..=12), `count` is 0, or the fleet does not parse or
/// names a type the scenario lacks.
pub fn generate(
    planner: &Planner,
    workload: &Workload,
    fleet: Fleet<'_>,
    count: usize,
) -> Result<Vec<PlanRequest>> {
    check(workload, count)?;
    let types = fleet.types(planner, workload)?;
    Ok(workload.requests_of_fleet(planner, count, types))
}

/// The requests of [`generate`] and the session replay of the same run:
/// the settings, the warm-up steps and `count` timed steps, timed step `k`
/// leading to the state of request `k` ([`Workload::requests_and_session`]).
///
/// # Errors
/// As [`generate`].
pub fn generate_session(
    planner: &Planner,
    workload: &Workload,
    fleet: Fleet<'_>,
    count: usize,
) -> Result<(Vec<PlanRequest>, SessionWorkload)> {
    check(workload, count)?;
    let types = fleet.types(planner, workload)?;
    Ok(workload.requests_and_session_of_fleet(planner, count, types))
}

/// The API's bounds on a generated workload.
fn check(workload: &Workload, count: usize) -> Result<()> {
    if workload.sensors == 0 || workload.sensors > MAX_SENSORS {
        bail!(
            "--sensors must be in 1..={MAX_SENSORS}, not {}",
            workload.sensors
        );
    }
    if workload.history > MAX_HISTORY_STEPS {
        bail!(
            "--history must be at most {MAX_HISTORY_STEPS}, not {}",
            workload.history
        );
    }
    if workload.horizon == 0 || workload.horizon > MAX_HORIZON {
        bail!(
            "--horizon must be in 1..={MAX_HORIZON}, not {}",
            workload.horizon
        );
    }
    if count == 0 {
        bail!("--count must be at least 1");
    }
    Ok(())
}

/// Reads a file of plan request bodies: a JSON array, or JSON lines.
///
/// # Errors
/// If the file cannot be read, is not valid JSON in either form (the error
/// names the line or element), or holds no request.
pub fn load(path: &Path) -> Result<Vec<PlanRequest>> {
    let text = fs::read_to_string(path)
        .with_context(|| format!("cannot read the requests file {}", path.display()))?;
    let reqs = parse(&text).with_context(|| {
        format!(
            "{} is neither a JSON array of plan requests nor JSON lines of them",
            path.display()
        )
    })?;
    if reqs.is_empty() {
        bail!("the requests file {} holds no request", path.display());
    }
    Ok(reqs)
}

/// Parses a JSON array of plan requests, or JSON lines of them.
///
/// # Errors
/// If the text is neither.
pub fn parse(text: &str) -> Result<Vec<PlanRequest>> {
    if text.trim_start().starts_with('[') {
        let values: Vec<serde_json::Value> =
            serde_json::from_str(text).context("invalid JSON array")?;
        values
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                serde_json::from_value(v)
                    .with_context(|| format!("element {i} is not a plan request"))
            })
            .collect()
    } else {
        text.lines()
            .enumerate()
            .filter(|(_, line)| !line.trim().is_empty())
            .map(|(i, line)| {
                serde_json::from_str(line)
                    .with_context(|| format!("line {} is not a plan request", i + 1))
            })
            .collect()
    }
}

/// Writes `reqs` to `path`: JSON lines if its name ends in `.jsonl` or
/// `.ndjson`, a JSON array otherwise.
///
/// # Errors
/// If the file cannot be written.
pub fn save(path: &Path, reqs: &[PlanRequest]) -> Result<()> {
    let lines = path
        .extension()
        .is_some_and(|e| e == "jsonl" || e == "ndjson");
    let mut out = Vec::new();
    if lines {
        for r in reqs {
            serde_json::to_writer(&mut out, r)?;
            out.push(b'\n');
        }
    } else {
        serde_json::to_writer(&mut out, reqs)?;
        out.push(b'\n');
    }
    let mut f =
        fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    f.write_all(&out)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// Serialises every request once, up front, so sending one costs no JSON
/// work in the generator.
///
/// # Errors
/// Never in practice (the request types always serialise).
pub fn bodies(reqs: &[PlanRequest]) -> Result<Vec<Bytes>> {
    reqs.iter()
        .map(|r| Ok(Bytes::from(serde_json::to_vec(r)?)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<PlanRequest> {
        parse(r#"[{"sensors":[{"id":"a","x":15,"y":15}]},{"sensors":[{"id":1,"x":25,"y":5}],"horizon":2}]"#)
            .unwrap()
    }

    #[test]
    fn arrays_and_json_lines_parse_alike() {
        let a = sample();
        assert_eq!(a.len(), 2);
        let lines: String = a
            .iter()
            .map(|r| format!("{}\n\n", serde_json::to_string(r).unwrap()))
            .collect();
        assert_eq!(parse(&lines).unwrap(), a);
    }

    #[test]
    fn bad_bodies_name_the_line_or_element() {
        let e = parse("{\"sensors\":[]}\n{oops}\n").unwrap_err();
        assert!(format!("{e:#}").contains("line 2"), "{e:#}");
        let e = parse(r#"[{"sensors":[]},{"nope":1}]"#).unwrap_err();
        assert!(format!("{e:#}").contains("element 1"), "{e:#}");
    }

    #[test]
    fn save_then_load_round_trips_in_both_forms() {
        let dir = tempfile::tempdir().unwrap();
        let reqs = sample();
        for name in ["r.json", "r.jsonl"] {
            let p = dir.path().join(name);
            save(&p, &reqs).unwrap();
            assert_eq!(load(&p).unwrap(), reqs);
        }
        let text = fs::read_to_string(dir.path().join("r.jsonl")).unwrap();
        assert_eq!(text.lines().count(), 2);
    }

    #[test]
    fn missing_and_empty_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let e = load(&dir.path().join("none.json")).unwrap_err();
        assert!(format!("{e:#}").contains("cannot read"), "{e:#}");
        let p = dir.path().join("empty.json");
        fs::write(&p, "[]").unwrap();
        assert!(format!("{:#}", load(&p).unwrap_err()).contains("no request"));
    }

    #[test]
    fn unknown_scenarios_and_bad_workloads_are_errors() {
        let e = planner_for("nope").unwrap_err().to_string();
        assert!(e.contains("paper-v10"), "{e}");
        let p = planner_for("paper-v10").unwrap();
        let w = Workload {
            sensors: 0,
            history: 0,
            horizon: 3,
            seed: 1,
        };
        assert!(generate(&p, &w, Fleet::Default, 1).is_err());
        let w = Workload {
            sensors: 2,
            horizon: 13,
            ..w
        };
        assert!(generate(&p, &w, Fleet::Default, 1).is_err());
        let w = Workload { horizon: 2, ..w };
        assert!(generate(&p, &w, Fleet::Default, 0).is_err());
        assert_eq!(generate(&p, &w, Fleet::Default, 2).unwrap().len(), 2);
    }
}
