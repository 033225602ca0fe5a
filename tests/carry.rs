//! A session's carry ([`vigil::estimator::Carry`]) changes no plan: on
//! random sessions of every built-in scenario, each step planned from the
//! carry of the previous one equals the stateless plan of the same state to
//! 1e-9, through dropped carries (an eviction), horizons that change, a
//! history shorter than the session's, and the scenarios the carry does
//! not apply to (uncertain looks, buildings, first detections), which plan
//! statelessly: those are the stateless plans to the bit.

mod common;

use std::sync::Arc;

use vigil::cancel::CancelToken;
use vigil::coordination::Objective;
use vigil::estimator::{Carry, CarryUse};
use vigil::planner::{Id, PlanInput, PlanResponse, Planner, SensorIn, TargetIn};
use vigil::scenario::{Cell, builtins};
use vigil::session::{Session, SessionSettings, StepRequest};

/// A small deterministic generator (xorshift64*), the tests' own.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

fn assert_same(carried: &PlanResponse, stateless: &PlanResponse, what: &str) {
    assert!(
        close(carried.expected_detections, stateless.expected_detections),
        "{what}: {} carried, {} stateless",
        carried.expected_detections,
        stateless.expected_detections
    );
    for (a, b) in carried
        .expected_by_step
        .iter()
        .zip(&stateless.expected_by_step)
    {
        assert!(close(*a, *b), "{what}: by step {a} against {b}");
    }
    for (a, b) in carried.plans.iter().zip(&stateless.plans) {
        assert!(
            close(a.expected_detections, b.expected_detections),
            "{what}: sensor {:?}: {} against {}",
            a.sensor,
            a.expected_detections,
            b.expected_detections
        );
    }
    match (&carried.bound, &stateless.bound) {
        (Some(a), Some(b)) => assert!(close(a.upper, b.upper), "{what}: bound {a:?} against {b:?}"),
        (None, None) => {}
        (a, b) => panic!("{what}: bound {a:?} against {b:?}"),
    }
}

/// Steps a session of `scenario` (`index` among the built-ins) for `steps`
/// steps, sensors walking at random, targets detected at random, planning
/// each step both ways.
fn run(index: usize, history: usize, steps: usize, seed: u64, objective: Objective) -> usize {
    let scenario = builtins().remove(index);
    let name = scenario.id.clone();
    let planner = Arc::new(Planner::new(scenario));
    let s = &planner.scenario;
    let mut rng = Rng(seed);
    let sensors = 6;
    let types: Vec<usize> = (0..sensors).map(|i| i % s.types.len()).collect();
    let mut cells: Vec<Cell> = types
        .iter()
        .map(|&ty| {
            loop {
                let c = Cell {
                    col: rng.below(s.cols as usize) as i32,
                    row: rng.below(s.rows as usize) as i32,
                };
                if s.is_free(ty, c) {
                    break c;
                }
            }
        })
        .collect();
    let mut session = Session::new(
        Arc::clone(&planner),
        SessionSettings {
            history_steps: Some(history.into()),
            ..SessionSettings::default()
        },
    );
    let mut carry = Carry::new();
    let mut carried_steps = 0;
    for step in 0..steps {
        for (c, &ty) in cells.iter_mut().zip(&types) {
            let moves: Vec<Cell> = common::one_step(s, *c, ty).into_iter().collect();
            let mut moves = moves;
            moves.sort_by_key(|m| (m.row, m.col));
            *c = moves[rng.below(moves.len())];
        }
        let detections = (0..rng.below(4))
            .map(|_| TargetIn {
                id: None,
                x: rng.unit() * s.cols as f64 * s.cell_size,
                y: rng.unit() * s.rows as f64 * s.cell_size,
                vx: rng.unit() * 8.0 - 4.0,
                vy: rng.unit() * 8.0 - 4.0,
            })
            .collect();
        let req = StepRequest {
            sensors: cells
                .iter()
                .zip(&types)
                .enumerate()
                .map(|(i, (&c, &ty))| {
                    let p = s.centre(c);
                    SensorIn {
                        id: Id::Text(format!("s{i}")),
                        x: p.x,
                        y: p.y,
                        sensor_type: Some(s.types[ty].name.clone()),
                    }
                })
                .collect(),
            detections,
            // Now and then another horizon, which the carried windows do
            // not serve.
            horizon: (step % 9 == 5).then(|| 2usize.into()),
            objective: Some(objective),
            ..StepRequest::default()
        };
        let prepared = session.prepare(&req);
        let input = PlanInput::new(s, &prepared.request).expect("a valid step");
        let stateless = planner.plan(&input);
        // An eviction now and then: the next step starts over.
        if rng.below(11) == 0 {
            carry = Carry::new();
        }
        let carried = planner
            .plan_carried(&input, &CancelToken::never(), &mut carry)
            .expect("never cancelled");
        assert_same(&carried, &stateless, &format!("{name}, step {step}"));
        if carry.last_use() == CarryUse::Stateless {
            let bare = |r: &PlanResponse| {
                let mut v = serde_json::to_value(r).expect("a response");
                v["compute_micros"] = 0.into();
                v
            };
            assert_eq!(bare(&carried), bare(&stateless), "{name}, step {step}");
        }
        carried_steps += usize::from(carry.last_use() == CarryUse::Continued);
        session.commit(prepared);
    }
    carried_steps
}

#[test]
fn carried_plans_equal_stateless_ones_on_every_builtin() {
    let count = builtins().len();
    for index in 0..count {
        let id = builtins()[index].id.clone();
        let carried = run(
            index,
            16,
            36,
            0x9E37_79B9 + index as u64,
            Objective::Detections,
        );
        let certain_open = {
            let s = &builtins()[index];
            !s.has_obstacles() && s.types.iter().all(|t| t.p_detect == 1.0)
        };
        // The carry is continued where it applies (all but the first step
        // and those after an eviction), and only there.
        if certain_open {
            assert!(carried > 25, "{id}: {carried} steps carried");
        } else {
            assert_eq!(carried, 0, "{id}");
        }
    }
}

#[test]
fn short_and_long_histories_carry_the_same_plans() {
    for (history, seed) in [(0, 1), (1, 2), (5, 3), (32, 4)] {
        run(0, history, 45, seed, Objective::Detections);
    }
}

/// First detections plan statelessly: a carried step, whose sums are the
/// same terms in another order, broke ties between paths otherwise.
#[test]
fn first_detections_plan_statelessly() {
    assert_eq!(run(0, 16, 12, 5, Objective::FirstDetections), 0);
}
