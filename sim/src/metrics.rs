//! Metrics: counts per step, averages per run, means and 95% confidence
//! intervals over seeds.

use serde::Serialize;
use vigil::coordination::JointReport;
use vigil::coordination::joint::JointStop;

/// What one step's counting found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepCount {
    /// Targets in the zone.
    pub in_zone: usize,
    /// Detected by at least one sensor.
    pub detected: usize,
    /// Of those, the ones no sensor had detected at an earlier step: what
    /// the intrusion objective's first step predicts.
    pub first_detected: usize,
    /// Detected by exactly one, two, three sensors.
    pub by_exactly: [usize; 3],
    /// Detected by four or more sensors.
    pub four_plus: usize,
    /// Distinct cells the sensors occupy after the step's move.
    pub cells: usize,
}

/// What the driver counted of the targets that entered the zone during the
/// measured window ([`crate::driver::Sim::entries`]): the counts behind
/// `detected_once`, `delay` and `missed`.
///
/// A target is counted when it is in the zone at the end of some measured
/// step and was not in it when the window started; its entry step is the
/// first such step, the one during which it crossed into the zone. A
/// target that crosses a corner within one step is never in the zone at a
/// step, could not have been detected, and is not counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Entries {
    /// Targets that entered the zone during the window.
    pub entered: usize,
    /// Of those, the ones detected at least once.
    pub detected: usize,
    /// Σ over the detected of (first detection step − entry step).
    pub delay_steps: usize,
    /// Of the entered, the ones no longer in the zone: they left it.
    pub left: usize,
    /// Of those that left, the ones never detected.
    pub left_undetected: usize,
}

impl Entries {
    /// The fraction of the entered targets detected at least once; 0 when
    /// none entered.
    pub fn detected_once(&self) -> f64 {
        if self.entered == 0 {
            return 0.0;
        }
        self.detected as f64 / self.entered as f64
    }

    /// The mean over the detected targets of the steps from entry to first
    /// detection (0: detected on the step it entered); `None` when none was
    /// detected, as a delay of 0 would read as instant detection.
    pub fn delay(&self) -> Option<f64> {
        (self.detected > 0).then(|| self.delay_steps as f64 / self.detected as f64)
    }

    /// The fraction of the targets that left the zone that were never
    /// detected; `None` when none has left. Targets still in the zone are
    /// in neither count: they may yet be detected.
    pub fn missed(&self) -> Option<f64> {
        (self.left > 0).then(|| self.left_undetected as f64 / self.left as f64)
    }
}

/// Accumulates the steps of one run.
#[derive(Debug, Clone, Default)]
pub struct RunAccumulator {
    steps: usize,
    ad: f64,
    zd: f64,
    af_sum: f64,
    af_steps: usize,
    d: [f64; 3],
    d4: f64,
    cells: f64,
    realized_next: f64,
    predicted_next: f64,
    plan_ms: Vec<f64>,
    /// Plan responses counted by [`RunAccumulator::add_plan_violations`].
    plans: usize,
    /// Of those, the ones with a separation violation.
    plans_violating: usize,
    /// Σ of their `separation_violations` (pairs of sensors × steps).
    violation_pairs: f64,
    /// Sensor plans in those responses, and those with a violation.
    sensor_plans: usize,
    sensor_plans_violating: usize,
    /// Each plan's certified gap (exact estimator).
    gaps: Vec<f64>,
    /// Joint plans, their rounds, and those that stopped at the gap target
    /// and on the time budget.
    joint_plans: usize,
    joint_rounds: usize,
    joint_at_target: usize,
    joint_out_of_budget: usize,
}

impl RunAccumulator {
    /// Adds one measured step.
    pub fn add(&mut self, c: StepCount) {
        self.steps += 1;
        self.ad += c.detected as f64;
        self.zd += (c.in_zone - c.detected) as f64;
        if c.in_zone > 0 {
            self.af_sum += c.detected as f64 / c.in_zone as f64;
            self.af_steps += 1;
        }
        for (d, n) in self.d.iter_mut().zip(c.by_exactly) {
            *d += n as f64;
        }
        self.d4 += c.four_plus as f64;
        self.cells += c.cells as f64;
    }

    /// Adds a plan response's `separation_violations`: `pairs`, the (step,
    /// pair of sensors) at which its paths are closer than the minimum
    /// separation, and `per_sensor`, each sensor plan's own count.
    pub fn add_plan_violations(&mut self, pairs: u32, per_sensor: impl IntoIterator<Item = u32>) {
        self.plans += 1;
        self.plans_violating += usize::from(pairs > 0);
        self.violation_pairs += f64::from(pairs);
        for v in per_sensor {
            self.sensor_plans += 1;
            self.sensor_plans_violating += usize::from(v > 0);
        }
    }

    /// Adds a planner's prediction for the next step and what happened.
    pub fn add_calibration(&mut self, predicted: f64, realized: usize) {
        self.predicted_next += predicted;
        self.realized_next += realized as f64;
    }

    /// Adds a plan's certified gap (its `bound.gap`).
    pub fn add_gap(&mut self, gap: f64) {
        self.gaps.push(gap);
    }

    /// Adds what a joint plan's rounds did (its `joint`).
    pub fn add_joint(&mut self, report: &JointReport) {
        self.joint_plans += 1;
        self.joint_rounds += report.rounds;
        self.joint_at_target += usize::from(report.stopped == JointStop::Gap);
        self.joint_out_of_budget += usize::from(report.stopped == JointStop::Budget);
    }

    /// Adds a plan round trip.
    pub fn add_plan_time(&mut self, ms: f64) {
        self.plan_ms.push(ms);
    }

    /// The run's averages. `detected_once`, `delay` and `missed` come from
    /// the driver's count of the targets that entered during the window.
    pub fn finish(mut self, entries: Entries) -> Metrics {
        let n = self.steps.max(1) as f64;
        let planner = !self.plan_ms.is_empty();
        self.plan_ms.sort_by(f64::total_cmp);
        self.gaps.sort_by(f64::total_cmp);
        // The nearest-rank percentile of sorted, non-empty samples.
        let pct =
            |v: &[f64], p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
        let gaps = !self.gaps.is_empty();
        let joint = self.joint_plans > 0;
        let per_joint = |n: usize| n as f64 / self.joint_plans as f64;
        Metrics {
            ad: self.ad / n,
            zd: self.zd / n,
            af: if self.af_steps > 0 {
                self.af_sum / self.af_steps as f64
            } else {
                0.0
            },
            d1s: self.d[0] / n,
            d2s: self.d[1] / n,
            d3s: self.d[2] / n,
            d4s: self.d4 / n,
            cells: self.cells / n,
            detected_once: entries.detected_once(),
            delay: entries.delay(),
            missed: entries.missed(),
            calibration: (planner && self.predicted_next > 0.0)
                .then(|| self.realized_next / self.predicted_next),
            plan_ms_p50: planner.then(|| pct(&self.plan_ms, 0.5)),
            plan_ms_p99: planner.then(|| pct(&self.plan_ms, 0.99)),
            violating_plans: (self.plans > 0)
                .then(|| self.plans_violating as f64 / self.plans as f64),
            violations_per_plan: (self.plans > 0).then(|| self.violation_pairs / self.plans as f64),
            violating_sensor_plans: (self.sensor_plans > 0)
                .then(|| self.sensor_plans_violating as f64 / self.sensor_plans as f64),
            gap_mean: gaps.then(|| self.gaps.iter().sum::<f64>() / self.gaps.len() as f64),
            gap_p50: gaps.then(|| pct(&self.gaps, 0.5)),
            joint_rounds: joint.then(|| per_joint(self.joint_rounds)),
            joint_at_target: joint.then(|| per_joint(self.joint_at_target)),
            joint_out_of_budget: joint.then(|| per_joint(self.joint_out_of_budget)),
        }
    }
}

/// Per-step averages of one run (or their means over seeds).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Metrics {
    /// Targets in the zone detected by at least one sensor.
    pub ad: f64,
    /// Targets in the zone detected by none.
    pub zd: f64,
    /// Mean over steps with targets of the fraction detected.
    pub af: f64,
    /// Detected by exactly one sensor.
    pub d1s: f64,
    /// Detected by exactly two sensors.
    pub d2s: f64,
    /// Detected by exactly three sensors.
    pub d3s: f64,
    /// Detected by four or more sensors (`D4+S`).
    pub d4s: f64,
    /// Distinct cells the sensors occupy after each move: the number of
    /// sensors when no two share a cell.
    pub cells: f64,
    /// Fraction of the targets that entered during the measured window that
    /// were detected at least once.
    pub detected_once: f64,
    /// Of the targets counted by `detected_once` that were detected, the
    /// mean number of steps from entry to first detection: the step at
    /// which some sensor first detected the target minus its entry step,
    /// the first step at whose end it was in the zone (the step during
    /// which it crossed into it); 0 when detected on the step it entered.
    /// `None` (JSON `null`) when no such target was detected; over seeds,
    /// the mean over the runs where it is defined.
    pub delay: Option<f64>,
    /// Of the targets counted by `detected_once` that have left the zone
    /// by the end of the run, the fraction never detected. Targets still
    /// in the zone at the end count neither as missed nor as not missed.
    /// `None` (JSON `null`) when none has left; over seeds, the mean over
    /// the runs where it is defined.
    pub missed: Option<f64>,
    /// Σ realized AD at the next step / Σ the plan's `expected_by_step[0]`
    /// (for a policy maximising first detections, the targets detected
    /// for the first time at the next step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub calibration: Option<f64>,
    /// Median plan round trip, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plan_ms_p50: Option<f64>,
    /// 99th percentile plan round trip, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plan_ms_p99: Option<f64>,
    /// Planner policies: the fraction of plan responses with
    /// `separation_violations > 0` (some pair of paths closer than the
    /// minimum separation at some step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub violating_plans: Option<f64>,
    /// Planner policies: the mean of the responses'
    /// `separation_violations` ((step, pair of sensors) too close per plan).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub violations_per_plan: Option<f64>,
    /// Planner policies: the fraction of sensor plans (one sensor's path in
    /// a response) closer than the minimum separation to another at some
    /// step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub violating_sensor_plans: Option<f64>,
    /// Exact estimator: the mean over the run's plans of the certified gap,
    /// `(upper − value) / upper`: how far below the best joint plan each
    /// plan can be, at most, as a fraction of the bound.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_mean: Option<f64>,
    /// Exact estimator: the median of the plans' certified gaps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_p50: Option<f64>,
    /// Joint coordination: the mean number of rounds after `iterated`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_rounds: Option<f64>,
    /// Joint coordination: the fraction of plans that reached the gap
    /// target.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_at_target: Option<f64>,
    /// Joint coordination: the fraction of plans stopped by the time
    /// budget (the rest settled: rounds in a row found nothing better).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_out_of_budget: Option<f64>,
}

/// Two-sided 97.5% quantile of Student's t with `df` degrees of freedom.
pub fn t_975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::INFINITY,
        1..=30 => TABLE[df - 1],
        _ => 1.96 + 2.4 / df as f64,
    }
}

/// Mean and half-width of the 95% confidence interval (0 for one sample).
pub fn mean_ci(xs: &[f64]) -> (f64, f64) {
    let n = xs.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let m = xs.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return (m, 0.0);
    }
    let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
    (m, t_975(n - 1) * (var / n as f64).sqrt())
}

/// Means and CI half-widths over seeds, field by field.
pub fn summarize(runs: &[Metrics]) -> (Metrics, Metrics) {
    fn field(runs: &[Metrics], f: impl Fn(&Metrics) -> f64) -> (f64, f64) {
        mean_ci(&runs.iter().map(f).collect::<Vec<_>>())
    }
    fn opt(runs: &[Metrics], f: impl Fn(&Metrics) -> Option<f64>) -> (Option<f64>, Option<f64>) {
        let v: Vec<f64> = runs.iter().filter_map(f).collect();
        if v.is_empty() {
            return (None, None);
        }
        let (m, c) = mean_ci(&v);
        (Some(m), Some(c))
    }
    let mut mean = Metrics::default();
    let mut ci = Metrics::default();
    (mean.ad, ci.ad) = field(runs, |m| m.ad);
    (mean.zd, ci.zd) = field(runs, |m| m.zd);
    (mean.af, ci.af) = field(runs, |m| m.af);
    (mean.d1s, ci.d1s) = field(runs, |m| m.d1s);
    (mean.d2s, ci.d2s) = field(runs, |m| m.d2s);
    (mean.d3s, ci.d3s) = field(runs, |m| m.d3s);
    (mean.d4s, ci.d4s) = field(runs, |m| m.d4s);
    (mean.cells, ci.cells) = field(runs, |m| m.cells);
    (mean.detected_once, ci.detected_once) = field(runs, |m| m.detected_once);
    // Undefined in a run without a detected (or a departed) entrant: such a
    // run has no figure to average, rather than a zero that is not one.
    (mean.delay, ci.delay) = opt(runs, |m| m.delay);
    (mean.missed, ci.missed) = opt(runs, |m| m.missed);
    (mean.calibration, ci.calibration) = opt(runs, |m| m.calibration);
    (mean.plan_ms_p50, ci.plan_ms_p50) = opt(runs, |m| m.plan_ms_p50);
    (mean.plan_ms_p99, ci.plan_ms_p99) = opt(runs, |m| m.plan_ms_p99);
    (mean.violating_plans, ci.violating_plans) = opt(runs, |m| m.violating_plans);
    (mean.violations_per_plan, ci.violations_per_plan) = opt(runs, |m| m.violations_per_plan);
    (mean.violating_sensor_plans, ci.violating_sensor_plans) =
        opt(runs, |m| m.violating_sensor_plans);
    (mean.gap_mean, ci.gap_mean) = opt(runs, |m| m.gap_mean);
    (mean.gap_p50, ci.gap_p50) = opt(runs, |m| m.gap_p50);
    (mean.joint_rounds, ci.joint_rounds) = opt(runs, |m| m.joint_rounds);
    (mean.joint_at_target, ci.joint_at_target) = opt(runs, |m| m.joint_at_target);
    (mean.joint_out_of_budget, ci.joint_out_of_budget) = opt(runs, |m| m.joint_out_of_budget);
    (mean, ci)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulates_per_step_averages() {
        let mut acc = RunAccumulator::default();
        acc.add(StepCount {
            in_zone: 10,
            detected: 4,
            first_detected: 4,
            by_exactly: [3, 1, 0],
            four_plus: 0,
            cells: 10,
        });
        acc.add(StepCount {
            in_zone: 0,
            detected: 0,
            first_detected: 0,
            by_exactly: [0, 0, 0],
            four_plus: 0,
            cells: 9,
        });
        acc.add(StepCount {
            in_zone: 5,
            detected: 5,
            first_detected: 5,
            by_exactly: [2, 1, 1],
            four_plus: 1,
            cells: 5,
        });
        // Four entered, two detected (after 2 and 3 steps), three left, one
        // of them undetected: the other undetected one is still in the zone.
        let m = acc.finish(Entries {
            entered: 4,
            detected: 2,
            delay_steps: 5,
            left: 3,
            left_undetected: 1,
        });
        assert_eq!(m.detected_once, 0.5);
        assert_eq!(m.delay, Some(2.5));
        assert_eq!(m.missed, Some(1.0 / 3.0));
        assert_eq!(m.ad, 3.0);
        assert_eq!(m.zd, 2.0);
        // Mean of 0.4 and 1.0, skipping the empty step.
        assert!((m.af - 0.7).abs() < 1e-12);
        assert_eq!((m.d1s, m.d2s, m.d3s), (5.0 / 3.0, 2.0 / 3.0, 1.0 / 3.0));
        assert_eq!(m.d4s, 1.0 / 3.0);
        assert_eq!(m.cells, 8.0);
        assert_eq!(m.calibration, None);
        // A local policy: no plans, no violation figures.
        assert_eq!((m.violating_plans, m.violations_per_plan), (None, None));
        assert_eq!(m.violating_sensor_plans, None);
    }

    #[test]
    fn counts_plans_with_separation_violations() {
        let mut acc = RunAccumulator::default();
        // Five responses of four sensor plans each: pairs and each plan's
        // own count (the pairs' counts, once per sensor of the pair).
        let per_sensor = [[0, 0, 0, 0], [2, 1, 3, 0], [0; 4], [0; 4], [1, 1, 0, 0]];
        for (pairs, per) in [0, 3, 0, 0, 1].into_iter().zip(per_sensor) {
            acc.add_plan_time(1.0);
            acc.add_plan_violations(pairs, per);
        }
        let m = acc.finish(Entries::default());
        assert_eq!(m.violating_plans, Some(0.4));
        assert_eq!(m.violations_per_plan, Some(0.8));
        assert_eq!(m.violating_sensor_plans, Some(5.0 / 20.0));
        let (mean, ci) = summarize(&[
            m,
            Metrics {
                violating_plans: Some(0.0),
                violations_per_plan: Some(0.0),
                cells: 4.0,
                d4s: 2.0,
                ..m
            },
        ]);
        assert_eq!(mean.violating_plans, Some(0.2));
        assert_eq!(mean.violations_per_plan, Some(0.4));
        assert!(ci.violating_plans.is_some_and(|c| c > 0.0));
        assert_eq!((mean.cells, mean.d4s), (2.0, 1.0));
    }

    #[test]
    fn summarizes_certified_gaps_and_joint_rounds() {
        let mut acc = RunAccumulator::default();
        for gap in [0.004, 0.001, 0.0, 0.002] {
            acc.add_plan_time(1.0);
            acc.add_gap(gap);
        }
        for (rounds, stopped) in [
            (3, JointStop::Gap),
            (7, JointStop::Budget),
            (2, JointStop::Settled),
            (0, JointStop::Gap),
        ] {
            acc.add_joint(&JointReport {
                rounds,
                stopped,
                micros: 1,
            });
        }
        let m = acc.finish(Entries::default());
        assert!(m.gap_mean.is_some_and(|g| (g - 0.00175).abs() < 1e-15));
        // The nearest-rank median of four: the second smallest.
        assert_eq!(m.gap_p50, Some(0.001));
        assert_eq!(m.joint_rounds, Some(3.0));
        assert_eq!(m.joint_at_target, Some(0.5));
        assert_eq!(m.joint_out_of_budget, Some(0.25));
        // A paper plan has no certificate, a non-joint plan no rounds.
        let m = RunAccumulator::default().finish(Entries::default());
        assert_eq!((m.gap_mean, m.gap_p50, m.joint_rounds), (None, None, None));
    }

    #[test]
    fn delay_and_missed_are_undefined_without_targets_to_count() {
        // Nothing entered: no fraction detected, no delay, nothing missed.
        let none = Entries::default();
        assert_eq!(
            (none.detected_once(), none.delay(), none.missed()),
            (0.0, None, None)
        );
        // Entered, none detected and none gone yet: no delay to average and
        // no target that could count as missed.
        let waiting = Entries {
            entered: 3,
            ..Entries::default()
        };
        assert_eq!((waiting.delay(), waiting.missed()), (None, None));
        // Every one detected on the step it entered, all gone: delay 0,
        // none missed.
        let instant = Entries {
            entered: 2,
            detected: 2,
            delay_steps: 0,
            left: 2,
            left_undetected: 0,
        };
        assert_eq!((instant.delay(), instant.missed()), (Some(0.0), Some(0.0)));
    }

    #[test]
    fn delay_and_missed_average_over_the_runs_that_define_them() {
        let run = |delay, missed| Metrics {
            detected_once: 0.5,
            delay,
            missed,
            ..Metrics::default()
        };
        let (mean, ci) = summarize(&[
            run(Some(1.0), Some(0.25)),
            run(Some(3.0), None),
            run(None, Some(0.75)),
            run(Some(2.0), Some(0.5)),
        ]);
        // Three delays and three fractions missed, not four with zeros.
        assert_eq!(mean.delay, Some(2.0));
        assert_eq!(mean.missed, Some(0.5));
        assert_eq!(ci.delay, Some(mean_ci(&[1.0, 3.0, 2.0]).1));
        assert_eq!(ci.missed, Some(mean_ci(&[0.25, 0.75, 0.5]).1));
        assert_eq!((mean.detected_once, ci.detected_once), (0.5, 0.0));
        let (mean, ci) = summarize(&[run(None, None), run(None, None)]);
        assert_eq!((mean.delay, mean.missed, ci.delay), (None, None, None));
    }

    #[test]
    fn confidence_interval_uses_student_t() {
        let (m, c) = mean_ci(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m, 2.5);
        // sd = 1.291, se = 0.6455, t(3) = 3.182.
        assert!((c - 3.182 * (5.0f64 / 3.0).sqrt() / 2.0).abs() < 1e-9);
    }
}
