//! A session's carry: what the exact estimator derived from a session's
//! looks at one step, kept for the next, so that a step does the work of
//! what changed instead of all of it.
//!
//! Two parts, each exact to the stateless estimator up to rounding:
//! - **Seen sets by sliding-window aggregation (two stacks).** A seen set
//!   is the union, over the steps held, of each step's looks pushed by the
//!   distance flown since. In emission coordinates (`r − v·age`, fixed over
//!   time) a step's intervals do not move, so the union over the window
//!   changes only by the newest step, which joins, and the oldest, which
//!   leaves. A union cannot forget, so the window is a queue of two stacks:
//!   the newer steps' union grows as they come ("back"); the older steps
//!   are held as suffix unions ("front": `front[i]` is the union of the
//!   i-th oldest step and all newer ones in the front), so that the oldest
//!   leaves by dropping `front[0]`. When the front runs out, every held
//!   step moves to it, its suffix unions rebuilt in a new base. A step then
//!   costs two merges of sorted interval lists per class, amortised, instead
//!   of the union of every look of the history.
//! - **Windows by difference.** The window of plan step `t + 1` at session
//!   step `N` covers the same instant as that of plan step `t` at `N + 1`;
//!   it lacks only what the newest looks added to the seen set and has
//!   what the oldest took away. The new windows are the old ones less the
//!   seen mass of that symmetric difference (a few pieces per ray), and the
//!   last one is filled whole.
//!
//! A carry is a pure function of the looks it holds and the planner that
//! made it: a step checks that its history is the carry's looks, one step
//! older, and starts over otherwise, so a stale or foreign carry gives the
//! stateless answer, never a wrong one. It applies to certain looks without
//! obstacles (the windows also need the one-window grid), for the
//! detections objective; other steps plan statelessly (the planner clears
//! the carry of a first-detections step).

use std::collections::VecDeque;

use super::rays::{ClassRays, LookKey, SourceRays, look_key};
use super::seen::RayHits;
use super::windows::Window;
use crate::scenario::{Look, Scenario, all_certain};

/// What the last step made of its carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CarryUse {
    /// It continued the carry.
    Continued,
    /// It had none, or one of another state, and started over.
    Rebuilt,
    /// The carry does not apply to it (uncertain looks, buildings, the
    /// paper's estimator, first detections), which planned statelessly.
    #[default]
    Stateless,
}

impl CarryUse {
    /// Its name in metrics.
    pub fn as_str(self) -> &'static str {
        match self {
            CarryUse::Continued => "used",
            CarryUse::Rebuilt => "rebuilt",
            CarryUse::Stateless => "none",
        }
    }
}

/// What a session's last step derived from its looks, to start the next
/// from. Empty until a step fills it; see the [module docs](self).
#[derive(Default)]
pub struct Carry {
    /// What the last step made of it.
    last: CarryUse,
    /// The planner whose rays and classes made it ([`Carry::planner`]).
    planner: u64,
    /// The steps held, oldest first: each step's looks and its rays' raw
    /// intervals (as of the step: pushed by nothing), per source.
    steps: VecDeque<HeldStep>,
    /// The absolute number of the newest step held.
    now: i64,
    /// The front's base: a front or back union holds `r − v·(now − base)`
    /// of what is at `r` now.
    base: i64,
    /// Per class: its speed and weight (checked against the planner's),
    /// its two stacks and the seen set it gave at the newest step.
    classes: Vec<ClassCarry>,
    /// The windows of plan steps `1..=T` at the newest step, when the
    /// one-window path made them.
    windows: Option<Vec<Window>>,
    /// Per class, the union one step before the newest and the base it
    /// was in, when the carry advanced by one step to it (what the windows
    /// are updated from).
    previous: Option<(Vec<RayHits>, i64)>,
}

struct HeldStep {
    looks: Vec<Look>,
    /// Per source (the planner's rays), the step's union at age 0.
    raw: Vec<RayHits>,
}

struct ClassCarry {
    rays: usize,
    speed: f64,
    weight: f64,
    /// Suffix unions of the oldest `front.len()` held steps, in the base.
    front: VecDeque<RayHits>,
    /// The union of every held step, in the base.
    union: RayHits,
    /// The union of the other, newer held steps, in the base (`None`:
    /// none).
    back: Option<RayHits>,
}

impl Carry {
    /// An empty carry: the next step starts from scratch.
    pub fn new() -> Self {
        Self::default()
    }

    /// Heap bytes held (the planner's, shared, aside).
    pub fn memory_bytes(&self) -> usize {
        let steps: usize = self
            .steps
            .iter()
            .map(|s| {
                s.looks.capacity() * std::mem::size_of::<Look>()
                    + s.raw.iter().map(RayHits::memory_bytes).sum::<usize>()
            })
            .sum();
        let classes: usize = self
            .classes
            .iter()
            .map(|c| {
                c.front.iter().map(RayHits::memory_bytes).sum::<usize>()
                    + c.back.as_ref().map_or(0, RayHits::memory_bytes)
                    + c.union.memory_bytes()
            })
            .sum();
        let windows: usize = self
            .windows
            .iter()
            .flatten()
            .map(Window::memory_bytes)
            .sum();
        std::mem::size_of::<Self>() + steps + classes + windows
    }

    /// True when it holds nothing.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }

    /// What the last step made of it.
    pub fn last_use(&self) -> CarryUse {
        self.last
    }

    fn clear(&mut self) {
        *self = Self::default();
    }

    /// The seen sets of `observed` (newest first) for `classes`, advancing
    /// the carry by one step when `observed` continues it, else rebuilding
    /// it; `None` (and the carry emptied) when the carry does not apply:
    /// uncertain looks or obstacles.
    pub(super) fn seen(
        &mut self,
        planner: u64,
        scenario: &Scenario,
        rays: &[SourceRays],
        classes: &[ClassRays],
        observed: &[Vec<Look>],
    ) -> Option<Vec<RayHits>> {
        if scenario.has_obstacles() || !observed.iter().all(|step| all_certain(step)) {
            self.clear();
            return None;
        }
        let same_classes = self.classes.len() == classes.len()
            && self
                .classes
                .iter()
                .zip(classes)
                .all(|(a, b)| a.rays == b.rays && a.speed == b.speed && a.weight == b.weight);
        let continues = self.planner == planner
            && same_classes
            && observed.len() >= 2
            && observed.len() - 1 <= self.steps.len()
            && observed[1..]
                .iter()
                .zip(self.steps.iter().rev())
                .all(|(o, held)| *o == held.looks);
        if continues {
            let previous = self
                .classes
                .iter_mut()
                .map(|c| std::mem::take(&mut c.union));
            self.previous = Some((previous.collect(), self.base));
            self.advance(scenario, rays, &observed[0], observed.len());
            self.last = CarryUse::Continued;
        } else {
            self.rebuild(planner, scenario, rays, classes, observed);
            self.last = CarryUse::Rebuilt;
        }
        Some(self.seen_now(rays))
    }

    /// Adds the step of `looks` as the newest, lets the oldest go so that
    /// `held` steps remain, and updates the seen sets.
    fn advance(&mut self, scenario: &Scenario, rays: &[SourceRays], looks: &[Look], held: usize) {
        let step = held_step(scenario, rays, looks);
        self.now += 1;
        self.steps.push_back(step);
        let newest = self.steps.len() - 1;
        let (now, base) = (self.now, self.base);
        for c in &mut self.classes {
            let raw = &self.steps[newest].raw[c.rays];
            let shift = c.speed * (base - now) as f64;
            c.back = Some(match c.back.take() {
                Some(back) => RayHits::merged(&back, 0.0, raw, shift),
                None => raw.clone().lifted(shift),
            });
        }
        while self.steps.len() > held {
            if self.classes.first().is_some_and(|c| c.front.is_empty()) {
                self.flip();
            }
            self.steps.pop_front();
            for c in &mut self.classes {
                c.front.pop_front();
            }
        }
        self.join(rays);
    }

    /// Moves every held step to the front, its suffix unions rebuilt in
    /// the base `now`.
    fn flip(&mut self) {
        self.base = self.now;
        let n = self.steps.len();
        for c in &mut self.classes {
            c.back = None;
            c.front.clear();
            let mut suffix: Option<RayHits> = None;
            for i in (0..n).rev() {
                let raw = &self.steps[i].raw[c.rays];
                // The step's age now: the stateless estimator's push.
                let shift = c.speed * (n - 1 - i) as f64;
                let union = match &suffix {
                    Some(s) => RayHits::merged(raw, shift, s, 0.0),
                    None => raw.clone().lifted(shift),
                };
                c.front.push_front(union.clone());
                suffix = Some(union);
            }
        }
    }

    /// Starts over from `observed` (newest first).
    fn rebuild(
        &mut self,
        planner: u64,
        scenario: &Scenario,
        rays: &[SourceRays],
        classes: &[ClassRays],
        observed: &[Vec<Look>],
    ) {
        self.clear();
        self.planner = planner;
        self.steps = observed
            .iter()
            .rev()
            .map(|looks| held_step(scenario, rays, looks))
            .collect();
        self.now = self.steps.len() as i64 - 1;
        self.classes = classes
            .iter()
            .map(|c| ClassCarry {
                rays: c.rays,
                speed: c.speed,
                weight: c.weight,
                front: VecDeque::new(),
                union: RayHits::default(),
                back: None,
            })
            .collect();
        self.flip();
        self.join(rays);
    }

    /// Each class's union of every held step: its front's and back's.
    fn join(&mut self, rays: &[SourceRays]) {
        for c in &mut self.classes {
            c.union = match (c.front.front(), &c.back) {
                (Some(f), Some(b)) => RayHits::merged(f, 0.0, b, 0.0),
                (Some(f), None) => f.clone(),
                (None, Some(b)) => b.clone(),
                (None, None) => RayHits::empty_of(rays[c.rays].dirs.len()),
            };
        }
    }

    /// Each class's seen set at the newest step: its union brought from
    /// the base to now, without what starts past a ray's exit.
    fn seen_now(&self, rays: &[SourceRays]) -> Vec<RayHits> {
        let lift_steps = (self.now - self.base) as f64;
        self.classes
            .iter()
            .map(|c| {
                c.union
                    .clone()
                    .lifted(c.speed * lift_steps)
                    .within(&rays[c.rays].beyond)
            })
            .collect()
    }

    /// The windows carried for `horizon` plan steps and, per class, what
    /// the seen set gained and lost since they were made
    /// ([`RayHits::change`], as of now), when the last step kept windows of
    /// the same horizon and this one continued it by one step. Both unions
    /// are compared in the base, where an interval that stayed has the
    /// same bits in both (unless the front was rebuilt in between), so
    /// the change holds only what changed.
    pub(super) fn take_windows(&mut self, horizon: usize) -> Option<(Vec<Window>, Vec<RayHits>)> {
        let windows = self.windows.take().filter(|w| w.len() == horizon)?;
        let (previous, base) = self.previous.take()?;
        let rebased = (self.base - base) as f64;
        let lift = (self.now - self.base) as f64;
        let change = self
            .classes
            .iter()
            .zip(&previous)
            .map(|(c, old)| {
                RayHits::change(&c.union, old, c.speed * rebased).lifted(c.speed * lift)
            })
            .collect();
        Some((windows, change))
    }

    /// Keeps `windows` (plan steps `1..=T` at the newest step) for the next
    /// step.
    pub(super) fn keep_windows(&mut self, windows: Vec<Window>) {
        self.windows = Some(windows);
    }
}

/// A step's looks and their rays' raw intervals per source.
fn held_step(scenario: &Scenario, rays: &[SourceRays], looks: &[Look]) -> HeldStep {
    let keys: Vec<Vec<Option<LookKey>>> = if rays.iter().any(|r| r.looks.is_some()) {
        vec![
            looks
                .iter()
                .map(|l| look_key(scenario, &l.region))
                .collect(),
        ]
    } else {
        Vec::new()
    };
    let observed = [looks.to_vec()];
    HeldStep {
        raw: rays
            .iter()
            .map(|sr| RayHits::new(sr, &observed, &keys, &[], 0.0))
            .collect(),
        looks: observed.into_iter().next().unwrap_or_default(),
    }
}
