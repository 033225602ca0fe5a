//! A world whose sources emit at other rates than the scenario the planner
//! is told (`--world-rates`, `--tell-world-rates`).
//!
//! A source's `rate` in a [`ScenarioSpec`] is its total rate, targets per
//! step over all its speed classes (`speeds` weights are normalised by
//! their sum), so scaling `rate` scales every class of the source alike and
//! keeps its speed mixture.

use serde::Serialize;
use vigil::scenario::{Scenario, ScenarioSpec};

/// Scale factors of the sources' rates, as given on the command line.
#[derive(Debug, Clone, PartialEq)]
pub enum RateScales {
    /// One factor for every source.
    All(f64),
    /// One factor per source, in the scenario's order.
    Each(Vec<f64>),
}

impl RateScales {
    /// Parses `3,0.3,1,0` (one factor per source) or `2` (one for every
    /// source). Every factor is a finite number ≥ 0 (0 silences a source);
    /// an empty entry, a negative, NaN or infinite factor is an error.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut scales = Vec::new();
        for (k, part) in text.split(',').enumerate() {
            let part = part.trim();
            let at = || format!("scale {} ({part:?})", k + 1);
            if part.is_empty() {
                return Err(format!(
                    "scale {} is empty: expected comma-separated factors ≥ 0, one per source \
                     (e.g. 3,0.3,1,0), or one for every source (e.g. 2)",
                    k + 1
                ));
            }
            let x: f64 = part
                .parse()
                .map_err(|_| format!("{} is not a number", at()))?;
            if !x.is_finite() {
                return Err(format!("{} is not finite", at()));
            }
            if x < 0.0 {
                return Err(format!("{} is negative", at()));
            }
            // `-0` is 0: a rate of −0.0 would print as such.
            scales.push(x + 0.0);
        }
        Ok(match scales.as_slice() {
            [x] => RateScales::All(*x),
            _ => RateScales::Each(scales),
        })
    }

    /// One factor per source of a scenario with `sources` sources; an
    /// error when a list's length is not that number.
    pub fn per_source(&self, sources: usize) -> Result<Vec<f64>, String> {
        match self {
            RateScales::All(x) => Ok(vec![*x; sources]),
            RateScales::Each(scales) if scales.len() == sources => Ok(scales.clone()),
            RateScales::Each(scales) => Err(format!(
                "{} scales for {sources} sources: give one per source, or one for every source",
                scales.len()
            )),
        }
    }
}

/// The world's rates in a run: what the report records.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorldRates {
    /// The factor of each source's rate, in the scenario's order.
    pub scales: Vec<f64>,
    /// The planner was told these rates (a scenario registered with them),
    /// not the scenario's own.
    pub told: bool,
}

/// `spec` with source `j`'s rate times `scales[j]`; `None` when the counts
/// differ.
pub fn scaled_spec(spec: &ScenarioSpec, scales: &[f64]) -> Option<ScenarioSpec> {
    if scales.len() != spec.sources.len() {
        return None;
    }
    let mut out = spec.clone();
    for (src, &k) in out.sources.iter_mut().zip(scales) {
        src.rate *= k;
    }
    Some(out)
}

/// The scenario `s` with its sources' rates scaled by `scales` (one per
/// source), validated: the world of a run with `--world-rates`.
pub fn world_scenario(s: &Scenario, scales: &[f64]) -> Result<Scenario, String> {
    let spec = scaled_spec(&s.spec, scales).ok_or_else(|| {
        format!(
            "{} scales for {} sources",
            scales.len(),
            s.spec.sources.len()
        )
    })?;
    Scenario::new(spec).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use vigil::scenario::{SourceSpec, SpeedSpec, paper_spec};

    use super::*;

    #[test]
    fn scales_parse_and_bad_ones_are_refused() {
        assert_eq!(RateScales::parse("2"), Ok(RateScales::All(2.0)));
        assert_eq!(RateScales::parse(" 0 "), Ok(RateScales::All(0.0)));
        assert_eq!(
            RateScales::parse("3, 0.3,1,0"),
            Ok(RateScales::Each(vec![3.0, 0.3, 1.0, 0.0]))
        );
        let zero = RateScales::parse("-0").expect("−0 is 0");
        assert_eq!(format!("{zero:?}"), "All(0.0)");
        for (bad, says) in [
            ("-1", "negative"),
            ("1,-0.5", "scale 2 (\"-0.5\") is negative"),
            ("nan", "not finite"),
            ("inf", "not finite"),
            ("1,-infinity", "not finite"),
            ("", "empty"),
            ("1,,2", "scale 2 is empty"),
            ("1,", "empty"),
            ("x", "not a number"),
            ("1;2", "not a number"),
        ] {
            let e = RateScales::parse(bad).expect_err(bad);
            assert!(e.contains(says), "{bad:?}: {e}");
        }
    }

    #[test]
    fn one_scale_per_source() {
        assert_eq!(RateScales::All(2.0).per_source(3), Ok(vec![2.0; 3]));
        let each = RateScales::Each(vec![1.0, 0.0]);
        assert_eq!(each.per_source(2), Ok(vec![1.0, 0.0]));
        let e = each.per_source(8).expect_err("2 for 8");
        assert!(e.contains("2 scales for 8 sources"), "{e}");
    }

    /// The total rate is scaled; a source's speed weights, and everything
    /// else, are kept, so each class's rate scales alike.
    #[test]
    fn scaling_scales_each_sources_total_rate() {
        let mut spec = paper_spec(10.0);
        spec.sources[1] = SourceSpec {
            speeds: Some(vec![
                SpeedSpec {
                    speed: 5.0,
                    weight: 3.0,
                },
                SpeedSpec {
                    speed: 15.0,
                    weight: 1.0,
                },
            ]),
            ..spec.sources[1].clone()
        };
        let s = Scenario::new(spec).expect("valid");
        let scales = [3.0, 2.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.5];
        let w = world_scenario(&s, &scales).expect("valid");
        for (j, &k) in scales.iter().enumerate() {
            assert_eq!(w.spec.sources[j].rate, s.spec.sources[j].rate * k);
            assert_eq!(w.sources[j].rate, s.sources[j].rate * k);
            assert_eq!(w.spec.sources[j].speeds, s.spec.sources[j].speeds);
            for (a, b) in w.classes_of(j).iter().zip(s.classes_of(j)) {
                assert_eq!(a.speed, b.speed);
                assert!((a.rate - b.rate * k).abs() <= 1e-12, "source {j}");
            }
        }
        assert_eq!(w.classes_of(1).len(), 2);
        assert_eq!((w.width, w.cols, w.horizon), (s.width, s.cols, s.horizon));
        assert!(world_scenario(&s, &[1.0; 3]).is_err());
        // Far too many targets: the scenario's own limit, an error.
        assert!(world_scenario(&s, &[1e12; 8]).is_err());
    }
}
