//! The cases the cost models are fitted on and checked against.

use vigil::coordination::{Coordination, Objective};
use vigil::planner::{EstimatorKind, Observed, PlanRequest, Planner};
use vigil::scenario::{
    FovSpec, Scenario, ScenarioSpec, SensorTypeSpec, SourceSpec, ZoneSpec, builtins, paper_spec,
    site_gates_spec,
};
use vigil_loadtest::workload::{Workload, paper_like_sources, site_with_classes, with_targets};

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Group {
    /// The load test's workloads.
    Workload,
    /// More plans, to spread the fit.
    Extra,
    /// The large plans.
    Large,
    /// Plans that maximise first detections.
    First,
    /// Precomputations.
    Precompute,
    /// Precomputations with obstacles: predicted by `cost::precompute_ms`
    /// whole (its obstacle terms are fitted apart, by hand, from these).
    Obstacles,
}

impl Group {
    /// The model that predicts the group's cases.
    pub fn model(self) -> Model {
        match self {
            Group::Workload | Group::Extra | Group::Large => Model::Plan,
            Group::First => Model::First,
            Group::Precompute => Model::Precompute,
            Group::Obstacles => Model::Whole,
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Group::Workload => "plans, load-test workloads",
            Group::Extra => "plans, other cases",
            Group::Large => "plans, the issue's large cases",
            Group::First => "plans, first detections",
            Group::Precompute => "precompute",
            Group::Obstacles => "precompute with obstacles",
        }
    }
}

/// The models of `vigil::cost`: `PLAN_MODEL`, `FIRST_MODEL` and
/// `PRECOMPUTE_MODEL`, or `cost::precompute_ms` whole (not refitted).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    Plan,
    First,
    Precompute,
    Whole,
}

pub enum Work {
    Plan {
        planner: usize,
        req: PlanRequest,
    },
    Precompute(Box<Scenario>),
    /// Predicted only (too long to run).
    PredictOnly(Box<Scenario>),
}

pub struct Case {
    pub name: String,
    pub group: Group,
    pub work: Work,
}

/// `k` sources of rate 0.3 spread evenly around the zone's edge, just
/// outside it (half-planes, like the paper's).
fn ring(w: f64, h: f64, k: usize) -> Vec<SourceSpec> {
    let perimeter = 2.0 * (w + h);
    (0..k)
        .map(|i| {
            let p = (i as f64 + 0.5) * perimeter / k as f64;
            let (x, y) = if p < w {
                (p, -1.0)
            } else if p < w + h {
                (w + 1.0, p - w)
            } else if p < 2.0 * w + h {
                (2.0 * w + h - p, h + 1.0)
            } else {
                (-1.0, perimeter - p)
            };
            SourceSpec::at(x, y, 0.3)
        })
        .collect()
}

/// A square zone of `side × side` cells of `cell` units, field of view
/// `fov`, `k` sources around it (eight: the paper's places), targets at 10
/// units per step.
fn lattice(side: usize, cell: f64, fov: FovSpec, k: usize) -> Scenario {
    let w = side as f64 * cell;
    let sources = if k == 8 {
        paper_like_sources(w)
    } else {
        ring(w, w, k)
    };
    Scenario::new(ScenarioSpec {
        name: Some(format!(
            "{side}×{side} cells of {cell}, {k} sources, {fov:?}"
        )),
        zone: ZoneSpec {
            width: w,
            height: w,
        },
        cell_size: cell,
        fov,
        sensor_speed: None,
        p_detect: None,
        sensor_types: None,
        no_go: None,
        obstacles: None,
        target_speed: Some(10.0),
        sources,
        horizon: Some(3.into()),
        min_separation: None,
        rays_per_pi: None,
    })
    .unwrap()
}

fn square(h: f64) -> FovSpec {
    FovSpec::Square { half_width: h }
}

fn circle(r: f64) -> FovSpec {
    FovSpec::Circle { radius: r }
}

/// The paper's scenario with more sensor types of fields of view `fovs`.
fn paper_with_types(fovs: &[FovSpec]) -> Scenario {
    let mut spec = paper_spec(10.0);
    spec.sensor_types = Some(
        fovs.iter()
            .enumerate()
            .map(|(i, &fov)| {
                (
                    format!("t{i}"),
                    SensorTypeSpec {
                        fov,
                        speed: None,
                        p_detect: None,
                        elevated: None,
                    },
                )
            })
            .collect(),
    );
    Scenario::new(spec).unwrap()
}

fn paper_fov(fov: FovSpec) -> Scenario {
    Scenario::new(ScenarioSpec {
        fov,
        ..paper_spec(10.0)
    })
    .unwrap()
}

pub struct Builder {
    pub planners: Vec<Planner>,
    pub cases: Vec<Case>,
    pub only: Option<String>,
}

impl Builder {
    fn wanted(&self, name: &str) -> bool {
        self.only.as_deref().is_none_or(|o| name.contains(o))
    }

    fn planner(&mut self, s: Scenario) -> usize {
        eprintln!("precomputing {}", s.id);
        self.planners.push(Planner::new(s));
        self.planners.len() - 1
    }

    fn plan(&mut self, group: Group, name: String, planner: usize, req: PlanRequest) {
        if self.wanted(&name) {
            self.cases.push(Case {
                name,
                group,
                work: Work::Plan { planner, req },
            });
        }
    }

    fn requests(&self, p: usize, w: &Workload, count: usize) -> Vec<PlanRequest> {
        w.requests(&self.planners[p], count)
    }

    fn pre(&mut self, name: String, s: Scenario, run: bool) {
        self.pre_in(Group::Precompute, name, s, run);
    }

    fn pre_in(&mut self, group: Group, name: String, s: Scenario, run: bool) {
        let name = format!("precompute {name}");
        if self.wanted(&name) {
            let s = Box::new(s);
            self.cases.push(Case {
                name,
                group,
                work: if run {
                    Work::Precompute(s)
                } else {
                    Work::PredictOnly(s)
                },
            });
        }
    }
}

/// `req` with every position (now and in the history) moved towards the
/// zone's centre, into a square of `half` cells either side of it.
fn crowd(s: &Scenario, req: &PlanRequest, half: f64) -> PlanRequest {
    let (cx, cy) = (0.5 * s.width, 0.5 * s.height);
    let (fx, fy) = (
        half * s.cell_size / (0.5 * s.width),
        half * s.cell_size / (0.5 * s.height),
    );
    let mut r = req.clone();
    for sensor in &mut r.sensors {
        sensor.x = cx + (sensor.x - cx) * fx;
        sensor.y = cy + (sensor.y - cy) * fy;
    }
    for p in r.history.iter_mut().flatten().flatten() {
        p.x = cx + (p.x - cx) * fx;
        p.y = cy + (p.y - cy) * fy;
    }
    r
}

fn set(req: &PlanRequest, f: impl FnOnce(&mut PlanRequest)) -> PlanRequest {
    let mut r = req.clone();
    f(&mut r);
    r
}

pub fn plan_cases(b: &mut Builder) {
    use Group::{Extra, Large, Workload as W};
    let reference = Workload::reference;
    let pv10 = b.planner(builtins().remove(0));
    let s10 = b.planners[pv10].scenario.clone();
    let base = b.requests(pv10, &reference(), 4);
    for (k, r) in base.iter().enumerate() {
        b.plan(W, format!("reference#{k}"), pv10, r.clone());
    }
    let r0 = &base[0];
    for t in [1usize, 2, 4, 6, 8, 10, 12] {
        let r = set(r0, |r| r.horizon = Some(t.into()));
        b.plan(W, format!("horizon {t}"), pv10, r);
    }
    for n in [1usize, 4, 16, 64, 256] {
        let w = Workload {
            sensors: n,
            ..reference()
        };
        let r = b.requests(pv10, &w, 1).remove(0);
        b.plan(W, format!("sensors {n}"), pv10, r);
    }
    for n in [0usize, 100, 1000, 5000, 20_000] {
        b.plan(W, format!("targets {n}"), pv10, with_targets(&s10, r0, n));
    }
    for h in [0usize, 4, 8, 32] {
        let w = Workload {
            history: h,
            ..reference()
        };
        let r = b.requests(pv10, &w, 1).remove(0);
        b.plan(W, format!("history {h}"), pv10, r);
    }
    for (name, c) in [
        ("iterated", Coordination::Iterated),
        ("none", Coordination::None),
    ] {
        let r = set(r0, |r| r.coordination = Some(c));
        b.plan(W, format!("coordination {name}"), pv10, r);
    }
    for d in [1usize, 3] {
        let r = set(r0, |r| r.min_separation = Some(d.into()));
        b.plan(W, format!("min_separation {d}"), pv10, r);
    }
    for (name, c) in [
        ("priority", Coordination::Priority),
        ("none", Coordination::None),
        ("iterated", Coordination::Iterated),
    ] {
        let r = set(r0, |r| {
            r.estimator = Some(EstimatorKind::Paper);
            r.coordination = Some(c);
        });
        b.plan(W, format!("paper estimator, {name}"), pv10, r);
    }
    let r = set(r0, |r| r.observed = Some(Observed::Zone));
    b.plan(W, "observed zone".into(), pv10, r);
    let pv15 = b.planner(builtins().remove(1));
    let r = b.requests(pv15, &reference(), 1).remove(0);
    b.plan(W, "paper-v15 reference".into(), pv15, r);
    let gates = b.planner(builtins().remove(2));
    let gate_reqs = b.requests(gates, &reference(), 2);
    b.plan(W, "site-gates".into(), gates, gate_reqs[0].clone());
    for k in [1usize, 2, 4] {
        let p = b.planner(site_with_classes(k));
        b.plan(W, format!("speed classes {k}"), p, gate_reqs[1].clone());
    }
    let fleet = b.planner(builtins().remove(3));
    for (f, spec) in vigil_sim::experiment::FLEETS.iter().enumerate() {
        let types =
            vigil_sim::driver::fleet_types(&b.planners[fleet].scenario, Some(spec), 10).unwrap();
        let r = reference()
            .requests_of_fleet(&b.planners[fleet], 1, types)
            .remove(0);
        b.plan(W, format!("fleet {f} ({spec})"), fleet, r);
    }
    let campus = b.planner(builtins().remove(4));
    for spec in ["drone:4,robot:6", "robot:10", "drone:10"] {
        let types =
            vigil_sim::driver::fleet_types(&b.planners[campus].scenario, Some(spec), 10).unwrap();
        let r = reference()
            .requests_of_fleet(&b.planners[campus], 1, types)
            .remove(0);
        b.plan(W, format!("campus {spec}"), campus, r);
    }

    // Spread: combinations, larger lattices, circles.
    let mix = |n: usize, t: usize, h: usize| Workload {
        sensors: n,
        history: h,
        horizon: t,
        seed: 2,
    };
    let combos: [(usize, usize, usize, usize, Coordination, EstimatorKind); 15] = [
        (64, 6, 16, 0, Coordination::Iterated, EstimatorKind::Exact),
        (
            16,
            12,
            32,
            5000,
            Coordination::Priority,
            EstimatorKind::Exact,
        ),
        (256, 3, 16, 0, Coordination::Iterated, EstimatorKind::Exact),
        (64, 12, 32, 0, Coordination::Iterated, EstimatorKind::Exact),
        (32, 8, 8, 2000, Coordination::None, EstimatorKind::Exact),
        (128, 4, 4, 500, Coordination::Priority, EstimatorKind::Exact),
        (64, 6, 16, 0, Coordination::Priority, EstimatorKind::Paper),
        (
            16,
            6,
            16,
            1000,
            Coordination::Iterated,
            EstimatorKind::Paper,
        ),
        (64, 3, 16, 0, Coordination::Iterated, EstimatorKind::Paper),
        (32, 12, 8, 2000, Coordination::None, EstimatorKind::Paper),
        (32, 3, 16, 0, Coordination::Iterated, EstimatorKind::Paper),
        (128, 3, 16, 0, Coordination::Iterated, EstimatorKind::Paper),
        (
            256,
            3,
            16,
            1000,
            Coordination::Priority,
            EstimatorKind::Paper,
        ),
        (128, 6, 16, 0, Coordination::Priority, EstimatorKind::Paper),
        (
            32,
            8,
            32,
            5000,
            Coordination::Iterated,
            EstimatorKind::Exact,
        ),
    ];
    for (n, t, h, targets, c, e) in combos {
        let r = b.requests(pv10, &mix(n, t, h), 1).remove(0);
        let r = if targets > 0 {
            with_targets(&s10, &r, targets)
        } else {
            r
        };
        let r = set(&r, |r| {
            r.coordination = Some(c);
            r.estimator = Some(e);
        });
        b.plan(
            Extra,
            format!("paper-v10 n{n} T{t} h{h} tg{targets} {c:?} {e:?}"),
            pv10,
            r,
        );
    }
    for side in [100usize, 300] {
        let p = b.planner(lattice(side, 10.0, square(30.0), 8));
        for (n, t) in [(10usize, 3usize), (10, 12), (64, 6)] {
            let r = b.requests(p, &mix(n, t, 16), 1).remove(0);
            b.plan(
                Extra,
                format!("lattice {side}² n{n} T{t} h16"),
                p,
                r.clone(),
            );
            if n == 64 {
                let r = set(&r, |r| r.coordination = Some(Coordination::Iterated));
                b.plan(
                    Extra,
                    format!("lattice {side}² n{n} T{t} h16 iterated"),
                    p,
                    r,
                );
            }
        }
    }
    let circ = b.planner(paper_fov(circle(30.0)));
    for (n, t, h, c) in [
        (10usize, 3usize, 16usize, Coordination::Priority),
        (10, 6, 16, Coordination::Priority),
        (4, 3, 4, Coordination::None),
        (20, 3, 8, Coordination::Iterated),
    ] {
        let r = b.requests(circ, &mix(n, t, h), 1).remove(0);
        let r = set(&r, |r| r.coordination = Some(c));
        b.plan(
            Extra,
            format!("circle r30 n{n} T{t} h{h} {c:?}"),
            circ,
            r.clone(),
        );
        if n == 10 && t == 3 {
            let s = b.planners[circ].scenario.clone();
            for targets in [0usize, 2000] {
                let r = with_targets(&s, &r, targets);
                b.plan(
                    Extra,
                    format!("circle r30 n{n} T{t} h{h} tg{targets}"),
                    circ,
                    r,
                );
            }
            let r = set(&r, |r| r.history = None);
            b.plan(Extra, format!("circle r30 n{n} T{t} h0"), circ, r);
        }
    }

    // Uncertain looks through circles: the seen pieces kept apart.
    let circ_p = b.planner(
        Scenario::new(ScenarioSpec {
            fov: circle(30.0),
            p_detect: Some(0.7),
            ..paper_spec(10.0)
        })
        .unwrap(),
    );
    for (n, t, h, c) in [
        (10usize, 3usize, 16usize, Coordination::Priority),
        (32, 6, 16, Coordination::Priority),
        (16, 3, 32, Coordination::Iterated),
        (10, 3, 0, Coordination::Priority),
    ] {
        let r = b.requests(circ_p, &mix(n, t, h), 1).remove(0);
        let r = set(&r, |r| r.coordination = Some(c));
        b.plan(
            Extra,
            format!("circle r30 p0.7 n{n} T{t} h{h} {c:?}"),
            circ_p,
            r,
        );
    }

    // Many obstacles near ground sensors, and a crowded ground fleet among
    // buildings: the excluded looks' own shadows cut each ray.
    let yard64 = b.planner(yard(64, 8, square(30.0)));
    for (n, t, c) in [
        (32usize, 6usize, Coordination::Priority),
        (16, 3, Coordination::Iterated),
    ] {
        let r = b.requests(yard64, &mix(n, t, 16), 1).remove(0);
        let r = set(&r, |r| r.coordination = Some(c));
        b.plan(Extra, format!("yard 64×8 n{n} T{t} {c:?}"), yard64, r);
    }
    for (n, t, c) in [
        (64usize, 3usize, Coordination::Priority),
        (32, 3, Coordination::Iterated),
    ] {
        let r = b.requests(campus, &mix(n, t, 8), 1).remove(0);
        let sc = &b.planners[campus].scenario;
        let free = |x: f64, y: f64| sc.is_free(0, sc.snap(vigil::geometry::Point::new(x, y)));
        let r = set(&crowd(sc, &r, 4.0), |r| {
            r.coordination = Some(c);
            // Those that the crowding put on a building stay out.
            r.sensors.retain(|p| free(p.x, p.y));
            for step in r.history.iter_mut().flatten() {
                step.retain(|p| free(p.x, p.y));
            }
        });
        b.plan(
            Extra,
            format!("crowded site-campus n{n} T{t} {c:?}"),
            campus,
            r,
        );
    }

    // Drones (uncertain, fast) among many reported targets (the targets
    // the excluded looks partly see, counted per view block), and many
    // drones (each view's rectangles masked by many looks).
    for (n, t, targets, c) in [
        (64usize, 6usize, 2000usize, Coordination::Iterated),
        (32, 3, 5000, Coordination::Priority),
        (128, 6, 200, Coordination::Iterated),
        (256, 3, 200, Coordination::Iterated),
    ] {
        let spec = format!("drone:{n}");
        let types =
            vigil_sim::driver::fleet_types(&b.planners[fleet].scenario, Some(&spec), n).unwrap();
        let r = mix(n, t, 8)
            .requests_of_fleet(&b.planners[fleet], 1, types)
            .remove(0);
        let r = with_targets(&b.planners[fleet].scenario, &r, targets);
        let r = set(&r, |r| r.coordination = Some(c));
        b.plan(
            Extra,
            format!("site-fleet {spec} T{t} tg{targets} {c:?}"),
            fleet,
            r,
        );
    }

    // Crowded fleets: every sensor within a few cells of the others, so
    // that each look meets most of the others' (the paper estimator's
    // cover, the exact estimator's rays through circles).
    for (n, t, c, e, p) in [
        (
            16usize,
            3usize,
            Coordination::Priority,
            EstimatorKind::Paper,
            pv10,
        ),
        (64, 3, Coordination::Priority, EstimatorKind::Paper, pv10),
        (32, 3, Coordination::Iterated, EstimatorKind::Paper, pv10),
        (64, 2, Coordination::Iterated, EstimatorKind::Paper, pv15),
        (32, 3, Coordination::Priority, EstimatorKind::Paper, circ),
        (16, 3, Coordination::Iterated, EstimatorKind::Paper, circ),
        (64, 3, Coordination::Priority, EstimatorKind::Exact, circ),
        (16, 6, Coordination::Iterated, EstimatorKind::Exact, circ),
    ] {
        let r = b.requests(p, &mix(n, t, 8), 1).remove(0);
        let r = crowd(&b.planners[p].scenario, &r, 3.0);
        let r = set(&r, |r| {
            r.coordination = Some(c);
            r.estimator = Some(e);
        });
        let name = &b.planners[p].scenario.id;
        b.plan(Extra, format!("crowded {name} n{n} T{t} {c:?} {e:?}"), p, r);
    }

    // The large plans.
    let big = b.requests(pv10, &mix(256, 12, 32), 1).remove(0);
    let iter = |r: PlanRequest| set(&r, |r| r.coordination = Some(Coordination::Iterated));
    b.plan(
        Large,
        "n256 T12 h32 tg20000 iterated".into(),
        pv10,
        iter(with_targets(&s10, &big, 20_000)),
    );
    b.plan(
        Large,
        "n256 T12 h32 tg5000 iterated".into(),
        pv10,
        iter(with_targets(&s10, &big, 5000)),
    );
    let mid = b.requests(pv10, &mix(64, 12, 32), 1).remove(0);
    b.plan(
        Large,
        "n64 T12 h32 tg2000 iterated".into(),
        pv10,
        iter(with_targets(&s10, &mid, 2000)),
    );
}

pub fn precompute_cases(b: &mut Builder, large: bool) {
    for side in [30usize, 100, 300, 1000, 2000] {
        let run = side < 2000 || large;
        b.pre(
            format!("lattice {side}²"),
            lattice(side, 10.0, square(30.0), 8),
            run,
        );
    }
    b.pre(
        "lattice 300², half width 27".into(),
        lattice(300, 10.0, square(27.0), 8),
        true,
    );
    for r in [15.0, 30.0, 60.0] {
        b.pre(format!("paper, circle r{r}"), paper_fov(circle(r)), true);
    }
    b.pre(
        "lattice 100², circle r30".into(),
        lattice(100, 10.0, circle(30.0), 8),
        true,
    );
    for k in [1usize, 4, 16, 64] {
        b.pre(
            format!("lattice 100², {k} sources"),
            lattice(100, 10.0, square(30.0), k),
            true,
        );
    }
    for k in [1usize, 16, 64] {
        b.pre(
            format!("cell 1, 50², circle r40, {k} sources"),
            lattice(50, 1.0, circle(40.0), k),
            true,
        );
    }
    b.pre(
        "cell 1, 100², circle r40, 64 sources".into(),
        lattice(100, 1.0, circle(40.0), 64),
        true,
    );
    b.pre(
        "cell 1, 200², circle r40, 64 sources".into(),
        lattice(200, 1.0, circle(40.0), 64),
        large,
    );
    b.pre(
        "cell 1, 500², circle r40, 4 sources".into(),
        lattice(500, 1.0, circle(40.0), 4),
        true,
    );
    b.pre(
        "cell 1, 2000², circle r40, 1 source".into(),
        lattice(2000, 1.0, circle(40.0), 1),
        large,
    );
    b.pre(
        "cell 1, 2000², circle r40, 64 sources".into(),
        lattice(2000, 1.0, circle(40.0), 64),
        false,
    );
    b.pre(
        "paper, types square 30+50".into(),
        paper_with_types(&[square(50.0)]),
        true,
    );
    b.pre(
        "paper, types square 30+20+50".into(),
        paper_with_types(&[square(20.0), square(50.0)]),
        true,
    );
    b.pre(
        "paper, types square 30 + circle 40".into(),
        paper_with_types(&[circle(40.0)]),
        true,
    );
    for (name, s) in builtins().into_iter().map(|s| (s.id.clone(), s)) {
        b.pre(name, s, true);
    }
    b.pre(
        "site-gates, 4 speed classes".into(),
        site_with_classes(4),
        true,
    );
    let mut big_gates = site_gates_spec();
    big_gates.cell_size = 2.0;
    b.pre(
        "site-gates, 2 m cells".into(),
        Scenario::new(big_gates).unwrap(),
        true,
    );
    let mut gates_circle = site_gates_spec();
    gates_circle.fov = circle(30.0);
    b.pre(
        "site-gates, circle r30".into(),
        Scenario::new(gates_circle).unwrap(),
        true,
    );
}

/// A 400 × 300 yard of 10 m cells, with ground robots and drones, two
/// sources and `n` obstacles (`n ≤ 64`), each a regular polygon of `k`
/// vertices and radius 6 on a grid, every other one a screen; fields of
/// view `fov` (the robots') and twice its size (the drones').
fn yard(n: usize, k: usize, fov: FovSpec) -> Scenario {
    let obstacles = (0..n)
        .map(|i| {
            let (cx, cy) = (25.0 + (i % 8) as f64 * 50.0, 20.0 + (i / 8) as f64 * 37.5);
            serde_json::json!({
                "polygon": (0..k).map(|j| {
                    let a = std::f64::consts::TAU * (j as f64 + 0.3) / k as f64;
                    [cx + 6.0 * a.cos(), cy + 6.0 * a.sin()]
                }).collect::<Vec<_>>(),
                "kind": if i % 2 == 0 { "building" } else { "screen" },
            })
        })
        .collect::<Vec<_>>();
    let wide = match fov {
        FovSpec::Square { half_width } => square(2.0 * half_width),
        FovSpec::Circle { radius } => circle(2.0 * radius),
    };
    let spec = serde_json::json!({
        "name": format!("yard, {n} obstacles of {k} vertices, {fov:?}"),
        "zone": {"width": 400, "height": 300}, "cell_size": 10, "target_speed": 5,
        "fov": fov,
        "sensor_types": {"drone": {"fov": wide, "speed": 3, "elevated": true}},
        "obstacles": obstacles,
        "sources": [{"x": -1, "y": 150, "rate": 0.5}, {"x": 401, "y": 100, "rate": 0.5}],
    });
    Scenario::new(serde_json::from_value(spec).unwrap()).unwrap()
}

/// Precomputations with obstacles, whose statistics cast rays: more
/// obstacles, more vertices, circles and smaller cells.
pub fn obstacle_cases(b: &mut Builder) {
    for (n, k) in [
        (4, 4),
        (16, 4),
        (64, 4),
        (16, 16),
        (64, 16),
        (16, 32),
        (64, 32),
    ] {
        b.pre_in(
            Group::Obstacles,
            format!("obstacles: yard {n}×{k}"),
            yard(n, k, square(20.0)),
            true,
        );
    }
    for (n, k) in [(16, 8), (64, 32)] {
        b.pre_in(
            Group::Obstacles,
            format!("obstacles: yard {n}×{k}, circle r20"),
            yard(n, k, circle(20.0)),
            true,
        );
    }
    let mut campus = vigil::scenario::site_campus_spec();
    b.pre_in(
        Group::Obstacles,
        "obstacles: site-campus".into(),
        Scenario::new(campus.clone()).unwrap(),
        true,
    );
    campus.cell_size = 5.0;
    b.pre_in(
        Group::Obstacles,
        "obstacles: site-campus, 5 m cells".into(),
        Scenario::new(campus.clone()).unwrap(),
        true,
    );
    campus.cell_size = 10.0;
    if let Some(list) = campus.obstacles.as_mut() {
        list.truncate(4);
    }
    b.pre_in(
        Group::Obstacles,
        "obstacles: site-campus, 4 obstacles".into(),
        Scenario::new(campus).unwrap(),
        true,
    );
}

/// Plans that maximise first detections: the reference workload's states
/// at each horizon and coordination, more sensors, and the other built-ins
/// (speed classes, typed fleets, buildings, circles).
pub fn first_cases(b: &mut Builder) {
    let first = |r: &PlanRequest, t: usize, c: Coordination| {
        set(r, |r| {
            r.objective = Some(Objective::FirstDetections);
            r.horizon = Some(t.into());
            r.coordination = Some(c);
        })
    };
    let reference = Workload::reference;
    let pv10 = b.planner(builtins().remove(0));
    let base = b.requests(pv10, &reference(), 4);
    for (k, r) in base.iter().enumerate() {
        let r = first(r, 3, Coordination::Priority);
        b.plan(Group::First, format!("first reference#{k}"), pv10, r);
    }
    let r0 = &base[0];
    for (name, c, horizons) in [
        (
            "priority",
            Coordination::Priority,
            &[1usize, 2, 4, 5, 6, 8][..],
        ),
        ("iterated", Coordination::Iterated, &[2, 3, 4, 5, 8][..]),
        ("none", Coordination::None, &[3][..]),
    ] {
        for &t in horizons {
            let r = first(r0, t, c);
            b.plan(Group::First, format!("first T{t} {name}"), pv10, r);
        }
    }
    let r = set(&first(r0, 3, Coordination::Priority), |r| {
        r.certify = Some(false)
    });
    b.plan(
        Group::First,
        "first T3 priority uncertified".into(),
        pv10,
        r,
    );
    for n in [4usize, 20, 40] {
        let w = Workload {
            sensors: n,
            ..reference()
        };
        let r = first(&b.requests(pv10, &w, 1)[0], 3, Coordination::Priority);
        b.plan(Group::First, format!("first sensors {n}"), pv10, r);
    }
    let r = set(&first(r0, 3, Coordination::Priority), |r| {
        r.observed = Some(Observed::Zone)
    });
    b.plan(Group::First, "first observed zone".into(), pv10, r);
    for n in [1usize, 4] {
        let w = Workload {
            sensors: n,
            ..reference()
        };
        let r = set(
            &first(&b.requests(pv10, &w, 1)[0], 3, Coordination::Priority),
            |r| r.observed = Some(Observed::Zone),
        );
        b.plan(
            Group::First,
            format!("first observed zone, sensors {n}"),
            pv10,
            r,
        );
    }
    let gates = b.planner(builtins().remove(2));
    let r = first(
        &b.requests(gates, &reference(), 1)[0],
        3,
        Coordination::Priority,
    );
    b.plan(Group::First, "first site-gates".into(), gates, r);
    for (scenario, fleets) in [
        (3, &["drone:4,robot:6"][..]),
        (4, &["drone:4,robot:6", "robot:10"][..]),
    ] {
        let p = b.planner(builtins().remove(scenario));
        let name = b.planners[p].scenario.id.clone();
        for spec in fleets {
            let types =
                vigil_sim::driver::fleet_types(&b.planners[p].scenario, Some(spec), 10).unwrap();
            let r = reference()
                .requests_of_fleet(&b.planners[p], 1, types)
                .remove(0);
            for (t, c) in [
                (3, Coordination::Priority),
                (3, Coordination::Iterated),
                (5, Coordination::Priority),
            ] {
                let r = first(&r, t, c);
                b.plan(
                    Group::First,
                    format!("first {name} {spec} T{t} {c:?}"),
                    p,
                    r,
                );
            }
        }
    }
    let circ = b.planner(paper_fov(circle(30.0)));
    let r = first(
        &b.requests(circ, &reference(), 1)[0],
        3,
        Coordination::Priority,
    );
    b.plan(Group::First, "first circle r30".into(), circ, r);
}
