//! Tests of `localiser`.

use super::*;

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

/// Row 5, column `col`, facing east.
fn cell(col: u8) -> GridPose {
    GridPose { x: 5, y: col, heading: Heading::East }
}

fn east(x: f64) -> Pose2 {
    Pose2 { x, y: 0.0, yaw_deg: 0.0 }
}

#[test]
fn a_wall_heard_before_corrects_the_later_readings() {
    // a wall 1.1 m east: heard from the start (97 cm), then no echo from the next cell
    let mut loc = Localiser::new(&CartoConfig::default());
    assert_eq!(loc.at_rest(ms(0), cell(0), east(0.0), Reading::Echo(0.97)), (0.0, 0.0));
    assert_eq!(loc.at_rest(ms(2000), cell(1), east(0.45), Reading::NoEcho), (0.0, 0.0));
    // from the cell after, the wheels say 0.90 m; the body is at 0.92 m (13 cm to the sonar)
    let (dx, dy) = loc.at_rest(ms(4000), cell(2), east(0.90), Reading::Echo(1.1 - 0.92 - 0.13));
    // two cells of wheel noise since the wall was placed, against two readings' noise
    let gain = two_readings_gain(2.0);
    assert!((dx - 0.02 * gain).abs() < 1e-3 && dy.abs() < 1e-9, "corrected by {dx}, gain {gain}");
    assert_eq!(loc.counters().applied, 1);
}

#[test]
fn two_readings_one_cell_apart_say_how_far_the_robot_went() {
    // 1.5 m to the wall: too far to keep as a surface, near enough to pair with the next
    let mut loc = Localiser::new(&CartoConfig::default());
    loc.at_rest(ms(0), cell(0), east(0.0), Reading::Echo(1.50));
    // the wheels say 0.45 m, the range says 0.47 m: one cell of wheel noise is corrected
    let (dx, _) = loc.at_rest(ms(2000), cell(1), east(0.45), Reading::Echo(1.03));
    let gain = two_readings_gain(1.0);
    assert!((dx - 0.02 * gain).abs() < 1e-3, "corrected by {dx}, gain {gain}");
}

/// The gain of a fix against an earlier reading `cells` moves of 0.45 m behind, with the
/// default robot: the wheels' variance over those moves (each adds its own) against two
/// readings' (noise and 1 cm steps).
fn two_readings_gain(cells: f64) -> f64 {
    let cfg = CartoConfig::default();
    let wheels = cells * (cfg.chassis.odometry_sigma_per_m * 0.45).powi(2);
    let readings = 2.0 * (cfg.sonar.sigma_m.powi(2) + 0.01f64.powi(2) / 12.0);
    wheels / (wheels + readings)
}

#[test]
fn a_touch_lets_the_next_reading_move_the_belief_further() {
    let fix = |touch: bool| {
        let mut loc = Localiser::new(&CartoConfig::default());
        loc.at_rest(ms(0), cell(0), east(0.0), Reading::Echo(0.80));
        if touch {
            loc.touched();
        }
        // the body was pushed 8 cm on unseen
        loc.at_rest(ms(2000), cell(1), east(0.45), Reading::Echo(0.80 - 0.45 - 0.08)).0
    };
    let (plain, touched) = (fix(false), fix(true));
    assert!((touched - 0.08).abs() < 0.015, "after a touch: {touched}");
    assert!(plain.abs() < 1e-9, "without a touch 8 cm is another object: {plain}");
}

#[test]
fn a_known_room_corrects_every_range_against_its_surfaces() {
    let mut loc = Localiser::new(&CartoConfig::default());
    loc.pin((-50..=50).map(|k| (1.2, f64::from(k) * 0.01)));
    loc.at_rest(ms(0), cell(0), east(0.0), Reading::Echo(1.07));
    loc.touched();
    // believed at 0.45, really at 0.50: 1.2 − 0.50 − 0.13
    let (dx, _) = loc.at_rest(ms(2000), cell(1), east(0.45), Reading::Echo(0.57));
    assert!((dx - 0.05).abs() < 0.015, "{dx}");
}

#[test]
fn a_look_aside_corrects_across_the_heading_against_the_plan() {
    let mut loc = Localiser::new(&CartoConfig::default());
    // a wall along y = 0.6, left of a robot driving east along y = 0
    loc.pin((-100..=300).map(|k| (f64::from(k) * 0.01, 0.6)));
    assert!(loc.has_plan());
    loc.at_rest(ms(0), cell(0), east(0.0), Reading::NoEcho);
    // four cells east with nothing ahead: the uncertainty across grows
    let before = loc.sigma_across_m(ms(20_000), east(1.8)).unwrap();
    loc.at_rest(ms(20_000), cell(4), east(1.8), Reading::NoEcho);
    // believed on y = 0, really 3 cm to the left (y = 0.03): looking 60° left, the range is
    // what the sensor model expects from there
    let look = Pose2 { yaw_deg: 60.0, ..east(1.8) };
    let fan = Fan { ray_offsets_deg: &loc.fan_deg, incidence_limit_deg: loc.incidence_limit_deg };
    let really = Pose2 { y: 0.03, ..look };
    let range = expected_range(loc.known_grid.as_ref().unwrap(), really, loc.mount_m, &fan, 2.0).unwrap();
    let (_, dy) = loc.at_look(ms(21_000), look, Reading::Echo(range));
    assert!(before > 0.005, "{before}");
    assert!((dy - 0.03).abs() < 0.012, "corrected by {dy}, across σ before {before}");
    assert!(loc.sigma_across_m(ms(21_000), east(1.8 + dy)).unwrap() < before);
}

#[test]
fn a_look_aside_turns_to_the_side_the_plan_has_the_nearer_surface_on() {
    let mut loc = Localiser::new(&CartoConfig::default());
    assert_eq!(loc.look_aside_side(east(0.0), 60.0, LOOK_ASIDE_MAX_M), None, "no plan, no look");
    loc.pin((-100..=100).map(|k| (f64::from(k) * 0.01, 0.5))); // left, 0.5 m
    assert_eq!(loc.look_aside_side(east(0.0), 60.0, LOOK_ASIDE_MAX_M), Some(1.0));
    loc.pin((-100..=100).map(|k| (f64::from(k) * 0.01, -0.3))); // right, nearer
    assert_eq!(loc.look_aside_side(east(0.0), 60.0, LOOK_ASIDE_MAX_M), Some(-1.0));
    // nothing within reach either side (the walls 3 m away): no look
    let mut far = Localiser::new(&CartoConfig::default());
    far.pin((-100..=100).map(|k| (f64::from(k) * 0.01, 3.0)));
    far.pin((-100..=100).map(|k| (f64::from(k) * 0.01, -3.0)));
    assert_eq!(far.look_aside_side(east(0.0), 60.0, LOOK_ASIDE_MAX_M), None);
    // a quarter turn faces a surface farther off, within the sonar's reach
    let mut open = Localiser::new(&CartoConfig::default());
    open.pin((-100..=100).map(|k| (f64::from(k) * 0.01, 2.5))); // left, 2.5 m
    assert_eq!(open.look_aside_side(east(0.0), 60.0, LOOK_ASIDE_MAX_M), None);
    assert_eq!(open.look_aside_side(east(0.0), 90.0, 3.0), Some(1.0));
    open.pin((-100..=100).map(|k| (f64::from(k) * 0.01, -2.2))); // right, nearer
    assert_eq!(open.look_aside_side(east(0.0), 90.0, 3.0), Some(-1.0));
    assert_eq!(far.look_aside_side(east(0.0), 90.0, 2.0), None, "beyond its reach: no look");
}

#[test]
fn without_a_plan_a_look_aside_corrects_nothing() {
    let mut loc = Localiser::new(&CartoConfig::default());
    loc.at_rest(ms(0), cell(0), east(0.0), Reading::Echo(0.5));
    let look = Pose2 { yaw_deg: 60.0, ..east(0.0) };
    assert_eq!(loc.at_look(ms(1000), look, Reading::Echo(0.5)), (0.0, 0.0));
}

/// Gen pillars 40, seed 1, room known: ranges expected from rays the sonar does not have
/// (a 7-ray fan against the profile's 5) met pillar edges the sensor's rays miss, and each
/// difference, on an oblique surface, pulled the belief 2 cm sideways, to 10 cm off.
#[test]
fn a_known_room_expects_each_range_from_the_rays_the_sensor_model_casts() {
    let profile = robot_model::profile::RobotProfile::default();
    let loc = Localiser::new(&CartoConfig::from_profile(&profile));
    let twin: Vec<f64> = robot_model::sensors::HcSr04::from_profile(&profile)
        .ray_angles()
        .iter()
        .map(|a| f64::from(a.to_degrees()))
        .collect();
    assert_eq!(loc.fan_deg.len(), twin.len());
    for (ours, theirs) in loc.fan_deg.iter().zip(&twin) {
        assert!((ours - theirs).abs() < 1e-4, "{:?} against {twin:?}", loc.fan_deg);
    }
    assert_eq!(sonar_fan_deg(7.5, 1), vec![0.0]);
}

#[test]
fn an_unknown_echo_or_silence_corrects_nothing_and_a_new_pose_forgets() {
    let mut loc = Localiser::new(&CartoConfig::default());
    assert_eq!(loc.at_rest(ms(0), cell(0), east(0.0), Reading::NoEcho), (0.0, 0.0));
    assert_eq!(loc.at_rest(ms(100), cell(0), east(0.0), Reading::Echo(0.5)), (0.0, 0.0));
    assert!(!loc.grid().written_cells().is_empty());
    loc.reset();
    assert!(loc.sigma_m().is_none());
    assert!(loc.grid().written_cells().is_empty());
    // the wall heard before the reset is not compared with any more
    assert_eq!(loc.at_rest(ms(200), cell(0), east(0.0), Reading::Echo(0.45)), (0.0, 0.0));
}

#[test]
fn the_same_echo_from_the_same_spot_is_learnt_once() {
    let mut loc = Localiser::new(&CartoConfig::default());
    loc.learn(east(0.0), Reading::Echo(1.5));
    let once = loc.grid().written_cells();
    for _ in 1..10 {
        loc.learn(east(0.0), Reading::Echo(1.5));
    }
    assert_eq!(loc.grid().written_cells(), once, "ten readings from one spot are one reading");
    loc.learn(Pose2 { y: 0.05, ..east(0.0) }, Reading::Echo(1.5));
    assert_ne!(loc.grid().written_cells(), once, "a step aside is a new reading");
}

#[test]
fn driving_without_readings_grows_the_uncertainty() {
    let mut loc = Localiser::new(&CartoConfig::default());
    loc.at_rest(ms(0), cell(0), east(0.0), Reading::NoEcho);
    let first = loc.sigma_m().unwrap_or_default();
    loc.at_rest(ms(5000), cell(4), east(2.0), Reading::NoEcho);
    assert!(loc.sigma_m().unwrap_or_default() > first, "{first} -> {:?}", loc.sigma_m());
}
