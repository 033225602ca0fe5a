//! The built-in scenarios: the paper's setting at two target speeds, and
//! three sites of our own (targets from directed gates; a mixed fleet
//! around no-go ground; the gated site among buildings and screens).

use std::collections::BTreeMap;

use super::{
    FovSpec, Heading, NoGoSpec, ObstacleSpec, Scenario, ScenarioSpec, SensorTypeSpec, SourceSpec,
    SpeedSpec, ZoneSpec,
};

/// Names of the built-in scenarios.
pub const BUILTIN_IDS: [&str; 5] = [
    "paper-v10",
    "paper-v15",
    "site-gates",
    "site-fleet",
    "site-campus",
];

/// The paper's setting: a 300×300 zone, 10-unit cells, square FOV of half
/// width 30, eight sources of rate 0.3 at a third and two thirds of each edge.
pub fn paper_spec(target_speed: f64) -> ScenarioSpec {
    let src = |x: f64, y: f64| SourceSpec::at(x, y, 0.3);
    ScenarioSpec {
        name: Some(format!("paper, target speed {target_speed}")),
        zone: ZoneSpec {
            width: 300.0,
            height: 300.0,
        },
        cell_size: 10.0,
        fov: FovSpec::Square { half_width: 30.0 },
        sensor_speed: None,
        p_detect: None,
        sensor_types: None,
        no_go: None,
        obstacles: None,
        target_speed: Some(target_speed),
        sources: vec![
            src(-1.0, 100.0),
            src(-1.0, 200.0),
            src(301.0, 100.0),
            src(301.0, 200.0),
            src(100.0, -1.0),
            src(200.0, -1.0),
            src(100.0, 301.0),
            src(200.0, 301.0),
        ],
        horizon: Some(3.into()),
        min_separation: None,
        rays_per_pi: None,
    }
}

/// Speeds of the `site-gates` scenario, metres per step: a walker, a
/// cyclist and a vehicle.
pub const SITE_WALKER: f64 = 1.5;
/// See [`SITE_WALKER`].
pub const SITE_CYCLIST: f64 = 5.0;
/// See [`SITE_WALKER`].
pub const SITE_VEHICLE: f64 = 12.0;

/// `site-gates`: a 400 m × 300 m industrial site in 10 m cells, watched by
/// sensors with the paper's 60 m square field of view. Targets come
/// through four openings in the fence, each with its own cone and mix:
/// - the main road gate on the west side, aimed east along the site road
///   (±15°): vehicles and walkers, two to one;
/// - a footpath gate in the south fence, aimed north-north-east (±20°):
///   mostly walkers, some cyclists;
/// - a delivery gate at the north-east corner, aimed along the yard
///   (200°, ±10°): vehicles and a few walkers, five to one;
/// - a breach in the north fence, where people climb over anywhere into
///   the half-plane below it (a 120° fan): walkers only.
pub fn site_gates_spec() -> ScenarioSpec {
    let class = |speed: f64, weight: f64| SpeedSpec { speed, weight };
    let gate = |x: f64, y: f64, rate: f64, direction: f64, spread: f64| SourceSpec {
        direction: Some(direction),
        spread: Some(spread),
        ..SourceSpec::at(x, y, rate)
    };
    ScenarioSpec {
        name: Some("site with gates: walkers, cyclists and vehicles".into()),
        zone: ZoneSpec {
            width: 400.0,
            height: 300.0,
        },
        cell_size: 10.0,
        fov: FovSpec::Square { half_width: 30.0 },
        sensor_speed: None,
        p_detect: None,
        sensor_types: None,
        no_go: None,
        obstacles: None,
        target_speed: None,
        sources: vec![
            SourceSpec {
                speeds: Some(vec![class(SITE_VEHICLE, 2.0), class(SITE_WALKER, 1.0)]),
                ..gate(-1.0, 150.0, 0.3, 0.0, 30.0)
            },
            SourceSpec {
                speeds: Some(vec![class(SITE_WALKER, 3.0), class(SITE_CYCLIST, 1.0)]),
                ..gate(120.0, -1.0, 0.1, 70.0, 40.0)
            },
            SourceSpec {
                speeds: Some(vec![class(SITE_VEHICLE, 5.0), class(SITE_WALKER, 1.0)]),
                ..gate(401.0, 301.0, 0.3, 200.0, 20.0)
            },
            SourceSpec {
                heading: Some(Heading::South),
                spread: Some(120.0),
                speeds: Some(vec![class(SITE_WALKER, 1.0)]),
                ..SourceSpec::at(250.0, 301.0, 0.03)
            },
        ],
        horizon: Some(3.into()),
        min_separation: None,
        rays_per_pi: None,
    }
}

/// The ground robot of `site-fleet`: the paper's 60 m square camera, one
/// cell per step, and a detection probability of 0.9.
pub fn site_robot() -> SensorTypeSpec {
    SensorTypeSpec {
        fov: FovSpec::Square { half_width: 30.0 },
        speed: None,
        p_detect: Some(0.9),
        elevated: None,
    }
}

/// The drone of `site-fleet`: a 100 m square view from altitude, three
/// cells per step, and a detection probability of 0.6 (smaller targets in
/// its image).
pub fn site_drone() -> SensorTypeSpec {
    SensorTypeSpec {
        fov: FovSpec::Square { half_width: 50.0 },
        speed: Some(3.into()),
        p_detect: Some(0.6),
        elevated: None,
    }
}

/// `site-fleet`: the yard of [`site_gates_spec`] (same gates, cones and
/// mixes of walkers, cyclists and vehicles), guarded by a mixed fleet
/// around ground no sensor may enter:
/// - sensor types `robot` ([`site_robot`]: 60 m view, 1 cell per step,
///   p_detect 0.9, also the type `default`) and `drone` ([`site_drone`]:
///   100 m view, 3 cells per step, p_detect 0.6);
/// - no-go zones: a warehouse in the middle of the yard (x 140–240,
///   y 100–170), a pond to the north-east (x 290–350, y 200–250) and a
///   fuel store by the west fence (x 30–70, y 220–270). Drones may not
///   fly over them either (restricted airspace); targets cross them.
pub fn site_fleet_spec() -> ScenarioSpec {
    let rect = |x0, y0, x1, y1| NoGoSpec { x0, y0, x1, y1 };
    let robot = site_robot();
    ScenarioSpec {
        name: Some("site with a fleet of robots and drones around no-go zones".into()),
        fov: robot.fov,
        p_detect: robot.p_detect,
        sensor_types: Some(BTreeMap::from([
            ("drone".to_owned(), site_drone()),
            ("robot".to_owned(), robot),
        ])),
        no_go: Some(vec![
            rect(140.0, 100.0, 240.0, 170.0),
            rect(290.0, 200.0, 350.0, 250.0),
            rect(30.0, 220.0, 70.0, 270.0),
        ]),
        ..site_gates_spec()
    }
}

/// `site-campus`: the gated site of [`site_gates_spec`] (same gates,
/// cones and mixes) built up, guarded by ground robots and drones:
/// - eight buildings, which block sight, end the flight of a target that
///   walks into them and keep robots off their cells: a main hall and a
///   workshop either side of the site road, a warehouse, an office block,
///   an octagonal silo, a depot, a gatehouse by the west gate and a shed
///   across the east fence;
/// - four screens, which block sight only: a tree line along the south
///   fence, a copse by the road, a hedge in the north-east and a clump of
///   trees in the north-west corner;
/// - sensor types `robot` (the ground robot of [`site_robot`], also the
///   type `default`) and `drone` ([`site_drone`], elevated: it sees over
///   every obstacle and flies over buildings).
pub fn site_campus_spec() -> ScenarioSpec {
    let building = |points: &[(f64, f64)]| ObstacleSpec {
        polygon: points.iter().map(|&(x, y)| [x, y]).collect(),
        kind: None,
    };
    let screen = |points: &[(f64, f64)]| ObstacleSpec {
        kind: Some("screen".into()),
        ..building(points)
    };
    let rect = |x0, y0, x1, y1| [(x0, y0), (x1, y0), (x1, y1), (x0, y1)];
    let octagon = |cx: f64, cy: f64, r: f64| -> Vec<(f64, f64)> {
        (0..8)
            .map(|i| {
                let a = std::f64::consts::FRAC_PI_4 * (f64::from(i) + 0.5);
                (cx + r * a.cos(), cy + r * a.sin())
            })
            .collect()
    };
    let robot = site_robot();
    ScenarioSpec {
        name: Some("campus: the gated site among buildings and trees, robots and drones".into()),
        fov: robot.fov,
        p_detect: robot.p_detect,
        sensor_types: Some(BTreeMap::from([
            (
                "drone".to_owned(),
                SensorTypeSpec {
                    elevated: Some(true),
                    ..site_drone()
                },
            ),
            ("robot".to_owned(), robot),
        ])),
        obstacles: Some(vec![
            building(&rect(60.0, 180.0, 130.0, 240.0)),
            building(&rect(60.0, 60.0, 120.0, 110.0)),
            building(&rect(170.0, 170.0, 250.0, 230.0)),
            building(&rect(180.0, 60.0, 230.0, 120.0)),
            building(&octagon(300.0, 90.0, 20.0)),
            building(&rect(290.0, 180.0, 360.0, 230.0)),
            building(&rect(20.0, 165.0, 35.0, 180.0)),
            building(&[
                (370.0, 100.0),
                (420.0, 110.0),
                (410.0, 150.0),
                (375.0, 140.0),
            ]),
            screen(&rect(140.0, 20.0, 240.0, 30.0)),
            screen(&octagon(150.0, 125.0, 12.0)),
            screen(&[
                (260.0, 240.0),
                (330.0, 265.0),
                (325.0, 275.0),
                (255.0, 250.0),
            ]),
            screen(&[(20.0, 250.0), (60.0, 250.0), (40.0, 285.0)]),
        ]),
        ..site_gates_spec()
    }
}

/// The built-in scenarios: `paper-v10` and `paper-v15` (the paper's),
/// `site-gates` ([`site_gates_spec`]), `site-fleet` ([`site_fleet_spec`])
/// and `site-campus` ([`site_campus_spec`]).
pub fn builtins() -> Vec<Scenario> {
    [
        paper_spec(10.0),
        paper_spec(15.0),
        site_gates_spec(),
        site_fleet_spec(),
        site_campus_spec(),
    ]
    .into_iter()
    .zip(BUILTIN_IDS)
    .map(|(spec, id)| Scenario::build(spec, Some(id)).expect("built-in specs are valid"))
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The building cells, marked row by row, are exactly the cells whose
    /// centre the closed polygons hold (site-campus, and buildings whose
    /// edges pass through cell centres).
    #[test]
    fn building_cells_are_the_centres_in_buildings() {
        let mut campus = site_campus_spec();
        campus
            .obstacles
            .as_mut()
            .expect("obstacles")
            .push(ObstacleSpec {
                polygon: vec![[15.0, 15.0], [55.0, 15.0], [55.0, 35.0], [15.0, 55.0]],
                kind: None,
            });
        let s = Scenario::new(campus).expect("valid");
        let robot = s.type_index("robot").expect("robot");
        let drone = s.type_index("drone").expect("drone");
        let mut blocked = 0;
        for i in 0..s.cell_count() {
            let c = s.cell_at(i);
            let inside = s.obstacles.in_building(s.centre(c));
            assert_eq!(s.blocked_for(robot, c).is_some(), inside, "{c:?}");
            assert!(s.blocked_for(drone, c).is_none());
            blocked += usize::from(inside);
        }
        assert!(blocked > 100, "{blocked}");
    }
}
