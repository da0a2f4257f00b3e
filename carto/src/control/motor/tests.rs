//! Tests of `motor`.

use super::*;
use crate::sensors::SensorEvent;

fn at_rest(s: &mut SensorState, now: Instant) {
    s.ingest(now, SensorEvent::Heading { cw_deg: 0.0 });
    for wheel in 0..4 {
        s.ingest(now, SensorEvent::Encoder { wheel, count: 0 });
    }
}

#[test]
fn a_turn_counts_as_turning_until_it_has_settled_also_when_stopped() {
    let mut motor = Motor::new(CartoConfig::default());
    let mut s = SensorState::default();
    let t0 = Instant::from_millis(1000);
    at_rest(&mut s, t0);
    assert!(!motor.is_turning(t0));
    motor.start_turn(t0, true, &s).unwrap();
    assert!(motor.is_turning(t0));
    // cut short by a STOP: the body may still rotate, so it counts as turning a while longer
    let stop = t0 + Duration::from_millis(200);
    motor.stop(stop);
    assert!(motor.is_turning(stop + Duration::from_millis(100)));
    assert!(!motor.is_turning(stop + SETTLE_AFTER_TURN));
    // a FORWARD is not a turn
    let later = stop + Duration::from_millis(1000);
    at_rest(&mut s, later);
    motor.start_forward(later, 0.3, &s).unwrap();
    assert!(!motor.is_turning(later));
}

/// Turns a robot whose yaw follows the commanded omega `delay_ms` late (a slow motor link),
/// at `deg_per_pct` degrees per second per percent; returns the outcome and the final yaw.
fn turn_with_dead_time(delay_ms: u64, deg_per_pct: f64) -> (Option<Result<(), MoveError>>, f64) {
    let mut motor = Motor::new(CartoConfig::default());
    let mut s = SensorState::default();
    let step = Duration::from_millis(10);
    let mut now = Instant::from_millis(1000);
    at_rest(&mut s, now);
    motor.start_turn(now, true, &s).unwrap();
    let mut sent = std::collections::VecDeque::new();
    let mut yaw = 0.0;
    while motor.is_busy() && now < Instant::from_millis(20_000) {
        sent.push_back(motor.command().omega);
        let applied = if sent.len() > (delay_ms / 10) as usize { sent.pop_front().unwrap_or(0) } else { 0 };
        yaw += f64::from(applied) * deg_per_pct * step.as_secs_f64();
        now += step;
        s.ingest(now, SensorEvent::Heading { cw_deg: -yaw });
        motor.poll(now, &s);
    }
    (motor.take_outcome(), yaw)
}

#[test]
fn a_turn_whose_nudges_overshoot_on_a_slow_link_ends_within_a_few_degrees() {
    // lossy-motor seed 2 (issue 10): 50 ms of link latency plus lost frames made every nudge
    // overshoot the 2° tolerance; after four corrections the turn failed, Carto kept its old
    // heading and refused every FORWARD after it. Such a turn now counts as done.
    let (outcome, yaw) = turn_with_dead_time(200, 3.0);
    assert!(matches!(outcome, Some(Ok(()))), "{outcome:?}");
    let off = (yaw + 90.0).abs();
    assert!(off > 2.0 && off <= 5.0, "ended {off:.2}° off the target");
    // Without the dead time the turn ends within its tolerance, as before.
    let (outcome, yaw) = turn_with_dead_time(0, 3.0);
    assert!(matches!(outcome, Some(Ok(()))) && (yaw + 90.0).abs() <= 2.0, "{outcome:?} {yaw}");
    // A faster robot on the same link overshoots by 6°: that turn still fails.
    let (outcome, _) = turn_with_dead_time(200, 6.0);
    assert!(matches!(outcome, Some(Err(MoveError::NotConverged { corrections: 4, .. }))), "{outcome:?}");
}
