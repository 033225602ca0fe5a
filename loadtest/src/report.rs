//! The summary of a whole `run.sh` session: the `/healthz` ceiling, the
//! in-process median, the fixed-rate run, the plan knee, and the HTTP
//! efficiency derived from them.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::generator::Summary;
use crate::inproc::{self, InprocReport};
use crate::session::SessionInprocReport;
use crate::sweep::SweepReport;

/// Everything `run.sh` measured, as `summarize --out` writes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Session {
    /// Cores the server was pinned to.
    pub server_cores: f64,
    /// The in-process plan times of the same requests.
    pub inproc: Option<InprocReport>,
    /// `/healthz`: the highest rate that met the SLO.
    pub healthz_knee_rate: Option<f64>,
    /// `/healthz`: the highest achieved rate of any step (the ceiling of
    /// the HTTP stack, or of the generator if that saturated first).
    pub healthz_max_achieved: Option<f64>,
    /// The fixed-rate plan run.
    pub fixed: Option<Summary>,
    /// The SLO of the plan sweep, ms.
    pub slo_ms: Option<f64>,
    /// Plans: the step at the knee.
    pub plan_knee: Option<Summary>,
    /// Plans: the highest achieved rate of any run (the sweep's steps and
    /// the fixed-rate run).
    pub plan_max_achieved: Option<f64>,
    /// Achieved plan rate at the knee per server core, divided by
    /// `1 / inproc median`.
    pub http_efficiency: Option<f64>,
    /// The same at the highest achieved plan rate of any run (the
    /// saturation throughput when a run overloaded the server, whatever its
    /// latency).
    pub http_efficiency_at_max: Option<f64>,
    /// Sessions: the in-process step times (`inproc --session`), with the
    /// stateless plans of the same states.
    #[serde(default)]
    pub session_inproc: Option<SessionInprocReport>,
    /// Sessions: the fixed-rate run of steps.
    #[serde(default)]
    pub session_fixed: Option<Summary>,
    /// The SLO of the session sweep, ms.
    #[serde(default)]
    pub session_slo_ms: Option<f64>,
    /// Sessions: the step at the knee.
    #[serde(default)]
    pub session_knee: Option<Summary>,
    /// Sessions: the highest achieved step rate of any run.
    #[serde(default)]
    pub session_max_achieved: Option<f64>,
    /// Achieved step rate at the session knee per server core, divided by
    /// `1 / in-process step median`.
    #[serde(default)]
    pub session_http_efficiency: Option<f64>,
    /// The same at the highest achieved step rate of any run.
    #[serde(default)]
    pub session_http_efficiency_at_max: Option<f64>,
}

fn read<T: DeserializeOwned>(path: Option<&Path>) -> Result<Option<T>> {
    path.map(|p| {
        let text = fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("{} is not the expected JSON", p.display()))
    })
    .transpose()
}

fn max_achieved(s: &SweepReport) -> Option<f64> {
    s.steps.iter().map(|x| x.achieved_rate).reduce(f64::max)
}

impl Session {
    /// Reads the results files given (each optional) and derives the
    /// efficiency.
    ///
    /// # Errors
    /// If a file given cannot be read or parsed.
    pub fn from_files(
        server_cores: f64,
        inproc: Option<&Path>,
        healthz_sweep: Option<&Path>,
        fixed: Option<&Path>,
        plan_sweep: Option<&Path>,
    ) -> Result<Self> {
        let inproc: Option<InprocReport> = read(inproc)?;
        let healthz: Option<SweepReport> = read(healthz_sweep)?;
        let fixed: Option<Summary> = read(fixed)?;
        let plan: Option<SweepReport> = read(plan_sweep)?;
        let plan_knee = plan.as_ref().and_then(|p| p.knee);
        let http_efficiency = match (plan_knee, inproc) {
            (Some(k), Some(i)) => Some(inproc::http_efficiency(
                k.achieved_rate,
                server_cores,
                i.median_ms,
            )),
            _ => None,
        };
        let plan_max_achieved = plan
            .as_ref()
            .and_then(max_achieved)
            .into_iter()
            .chain(fixed.map(|f| f.achieved_rate))
            .reduce(f64::max);
        let http_efficiency_at_max = match (plan_max_achieved, inproc) {
            (Some(m), Some(i)) => Some(inproc::http_efficiency(m, server_cores, i.median_ms)),
            _ => None,
        };
        Ok(Session {
            server_cores,
            inproc,
            healthz_knee_rate: healthz.as_ref().and_then(|h| h.knee_rate),
            healthz_max_achieved: healthz.as_ref().and_then(max_achieved),
            fixed,
            slo_ms: plan.as_ref().map(|p| p.slo_ms),
            plan_knee,
            plan_max_achieved,
            http_efficiency,
            http_efficiency_at_max,
            session_inproc: None,
            session_fixed: None,
            session_slo_ms: None,
            session_knee: None,
            session_max_achieved: None,
            session_http_efficiency: None,
            session_http_efficiency_at_max: None,
        })
    }

    /// Adds the session runs' files given (each optional): the in-process
    /// steps, the fixed-rate run and the sweep, and derives their
    /// efficiency as for plans.
    ///
    /// # Errors
    /// If a file given cannot be read or parsed.
    pub fn with_sessions(
        mut self,
        inproc: Option<&Path>,
        fixed: Option<&Path>,
        sweep: Option<&Path>,
    ) -> Result<Self> {
        let inproc: Option<SessionInprocReport> = read(inproc)?;
        let fixed: Option<Summary> = read(fixed)?;
        let sweep: Option<SweepReport> = read(sweep)?;
        let knee = sweep.as_ref().and_then(|p| p.knee);
        let max = sweep
            .as_ref()
            .and_then(max_achieved)
            .into_iter()
            .chain(fixed.map(|f| f.achieved_rate))
            .reduce(f64::max);
        let median = inproc.map(|i| i.steps.median_ms);
        let eff = |rate: Option<f64>| {
            rate.zip(median)
                .map(|(r, m)| inproc::http_efficiency(r, self.server_cores, m))
        };
        self.session_http_efficiency = eff(knee.map(|k| k.achieved_rate));
        self.session_http_efficiency_at_max = eff(max);
        self.session_inproc = inproc;
        self.session_fixed = fixed;
        self.session_slo_ms = sweep.as_ref().map(|p| p.slo_ms);
        self.session_knee = knee;
        self.session_max_achieved = max;
        Ok(self)
    }

    /// A human-readable summary, several lines.
    pub fn describe(&self) -> String {
        let mut out = String::new();
        out += &format!("server cores: {}\n", self.server_cores);
        if let Some(i) = &self.inproc {
            out += &format!(
                "in process: median {:.3} ms, p90 {:.3}, p99 {:.3} ({:.0} plans/s per core)\n",
                i.median_ms, i.p90_ms, i.p99_ms, i.plans_per_s_per_core
            );
        }
        out += &format!(
            "/healthz: knee {}/s, highest achieved {}/s\n",
            opt(self.healthz_knee_rate, 0),
            opt(self.healthz_max_achieved, 0)
        );
        if let Some(x) = &self.fixed {
            out += &fixed_line("plans", x);
            out += "\n";
        }
        out += &knee_line(
            "plan",
            self.slo_ms,
            self.plan_knee.as_ref(),
            self.plan_max_achieved,
            "the first step failed the SLO",
        );
        out += "\n";
        out += &format!(
            "HTTP efficiency = (knee throughput / server cores) / (1 / in-process median) = {}",
            opt(self.http_efficiency, 3)
        );
        out += &format!(
            "\n  at the highest plan rate achieved in any run (saturation, any latency): {}",
            opt(self.http_efficiency_at_max, 3)
        );
        if let Some(i) = &self.session_inproc {
            out += &format!(
                "\nsessions in process: median {:.3} ms, p90 {:.3}, p99 {:.3} ({:.0} steps/s per core)",
                i.steps.median_ms, i.steps.p90_ms, i.steps.p99_ms, i.steps_per_s_per_core
            );
            if let Some(p) = &i.stateless {
                out += &format!(
                    "; the stateless plans of the same states, timed alternately: median {:.3} ms",
                    p.median_ms
                );
            }
        }
        if let Some(x) = &self.session_fixed {
            out += "\n";
            out += &fixed_line("session steps", x);
        }
        if self.session_slo_ms.is_some() || self.session_max_achieved.is_some() {
            out += "\n";
            out += &knee_line(
                "session",
                self.session_slo_ms,
                self.session_knee.as_ref(),
                self.session_max_achieved,
                "the first step failed the SLO or no sweep",
            );
            out += &format!(
                "\nsession HTTP efficiency at the knee: {}; at the highest step rate achieved: {}",
                opt(self.session_http_efficiency, 3),
                opt(self.session_http_efficiency_at_max, 3)
            );
        }
        out
    }
}

/// `x` or `-`, with `digits` decimals.
fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or_else(|| "-".to_owned(), |v| format!("{v:.digits$}"))
}

/// One line on a fixed-rate run of `what` (no newline).
fn fixed_line(what: &str, x: &Summary) -> String {
    format!(
        "{what} at {:.0}/s: achieved {:.1}/s, p50 {:.3} ms, p90 {:.3}, p99 {:.3}, p99.9 {:.3}, max {:.3}, errors {}, shed {}",
        x.target_rate,
        x.achieved_rate,
        x.p50_ms,
        x.p90_ms,
        x.p99_ms,
        x.p999_ms,
        x.max_ms,
        x.errors,
        x.shed
    )
}

/// One line on a sweep's knee (no newline); `none` says why there is none.
fn knee_line(
    what: &str,
    slo_ms: Option<f64>,
    knee: Option<&Summary>,
    max_achieved: Option<f64>,
    none: &str,
) -> String {
    match knee {
        Some(k) => format!(
            "{what} knee (p99 ≤ {} ms): {:.0}/s target, {:.1}/s achieved, p50 {:.3} ms, p99 {:.3}; highest achieved {}/s",
            opt(slo_ms, 1),
            k.target_rate,
            k.achieved_rate,
            k.p50_ms,
            k.p99_ms,
            opt(max_achieved, 0)
        ),
        None => format!(
            "{what} knee: none ({none}); highest achieved {}/s",
            opt(max_achieved, 0)
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(target: f64, achieved: f64, p99: f64) -> Summary {
        Summary {
            target_rate: target,
            achieved_rate: achieved,
            duration_s: 10.0,
            requests: 100,
            errors: 0,
            shed: 0,
            p50_ms: p99 / 2.0,
            p90_ms: p99,
            p99_ms: p99,
            p999_ms: p99,
            max_ms: p99,
        }
    }

    #[test]
    fn the_session_combines_the_files_and_derives_the_efficiency() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, v: &dyn erased::Json| {
            let p = dir.path().join(name);
            fs::write(&p, v.json()).unwrap();
            p
        };
        let inproc = InprocReport {
            requests: 10,
            iterations: 100,
            median_ms: 0.5,
            p90_ms: 0.6,
            p99_ms: 0.7,
            mean_ms: 0.55,
            min_ms: 0.4,
            max_ms: 0.8,
            plans_per_s_per_core: 2000.0,
        };
        let sweep = SweepReport {
            slo_ms: 2.0,
            min_achieved: 0.95,
            knee_rate: Some(1600.0),
            knee: Some(summary(1600.0, 1590.0, 1.8)),
            stopped: "2000.0/s failed the SLO".into(),
            steps: vec![summary(1600.0, 1590.0, 1.8), summary(2000.0, 1700.0, 40.0)],
        };
        let i = write("i.json", &inproc);
        let p = write("p.json", &sweep);
        let s = Session::from_files(1.0, Some(&i), None, None, Some(&p)).unwrap();
        // 1590/s on one core × 0.5 ms = 0.795.
        assert!((s.http_efficiency.unwrap() - 0.795).abs() < 1e-9);
        assert_eq!(s.plan_max_achieved, Some(1700.0));
        assert!((s.http_efficiency_at_max.unwrap() - 0.85).abs() < 1e-9);
        assert!(s.describe().contains("0.795"), "{}", s.describe());
        // The fixed-rate run counts towards the highest achieved rate.
        let f = write("f.json", &summary(2000.0, 1800.0, 90.0));
        let s = Session::from_files(2.0, Some(&i), None, Some(&f), Some(&p)).unwrap();
        assert_eq!(s.plan_max_achieved, Some(1800.0));
        assert!((s.http_efficiency_at_max.unwrap() - 0.45).abs() < 1e-9);
        assert!((s.http_efficiency.unwrap() - 0.3975).abs() < 1e-9);
        assert_eq!(s.healthz_knee_rate, None);
        // Sessions: the same derivation from their own files.
        let si = crate::session::SessionInprocReport {
            steps: InprocReport {
                median_ms: 0.25,
                ..inproc
            },
            steps_per_s_per_core: 4000.0,
            warmup_steps: 43,
            sessions: 1,
            stateless: Some(inproc),
        };
        let si = write("si.json", &si);
        let sf = write("sf.json", &summary(2000.0, 1900.0, 4.0));
        let s = Session::from_files(1.0, Some(&i), None, None, Some(&p))
            .unwrap()
            .with_sessions(Some(&si), Some(&sf), Some(&p))
            .unwrap();
        // 1590/s × 0.25 ms; the fixed run's 1900/s is the highest achieved.
        assert!((s.session_http_efficiency.unwrap() - 0.3975).abs() < 1e-9);
        assert_eq!(s.session_max_achieved, Some(1900.0));
        assert!((s.session_http_efficiency_at_max.unwrap() - 0.475).abs() < 1e-9);
        assert_eq!(s.session_slo_ms, Some(2.0));
        assert!(s.describe().contains("session knee"), "{}", s.describe());
        assert!(s.describe().contains("0.475"), "{}", s.describe());
        let missing = dir.path().join("none.json");
        assert!(Session::from_files(1.0, Some(&missing), None, None, None).is_err());
    }

    /// Serialising test values of different types through one closure.
    mod erased {
        pub trait Json {
            fn json(&self) -> String;
        }
        impl<T: serde::Serialize> Json for T {
            fn json(&self) -> String {
                serde_json::to_string(self).unwrap()
            }
        }
    }
}
