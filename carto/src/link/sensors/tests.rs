//! Tests of `sensors`.

use super::*;

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

#[test]
fn imu_drift_at_rest_is_learnt_from_the_wheels_and_removed() {
    let cfg = CartoConfig::default();
    let mut s = SensorState::default();
    // 30 s at rest: the wheels do not move, the NavX reading grows clockwise by 0.5°/min.
    for k in 0..=300u64 {
        let at = ms(k * 100);
        s.ingest(at, SensorEvent::Heading { cw_deg: 0.5 * (k as f64 * 0.1) / 60.0 });
        for wheel in 0..4 {
            s.ingest(at, SensorEvent::Encoder { wheel, count: 0 });
        }
        s.estimate_imu_drift(at, &cfg, false);
    }
    let raw = -0.25; // after 30 s the raw yaw is −0.25°
    assert!((s.imu_drift_deg() - raw).abs() < 0.03, "estimate {:.3}", s.imu_drift_deg());
    assert!(s.yaw_deg().unwrap().value.abs() < 0.03, "corrected yaw {:.3}", s.yaw_deg().unwrap().value);
    // off: the raw heading stays
    let off = without_drift();
    let mut t = SensorState::default();
    t.ingest(ms(0), SensorEvent::Heading { cw_deg: 1.0 });
    t.estimate_imu_drift(ms(0), &off, false);
    assert_eq!(t.yaw_deg().unwrap().value, -1.0);
}

/// Feeds one IMU sample (`yaw_deg` counter-clockwise) and four wheel counts giving the
/// wheels' heading `wheel_deg`, then runs the smoothing and the drift estimate.
fn feed(s: &mut SensorState, cfg: &CartoConfig, at: Instant, yaw_deg: f64, wheel_deg: f64, turning: bool) {
    let c = wheel_deg_to_counts(cfg, wheel_deg);
    s.ingest(at, SensorEvent::Heading { cw_deg: -yaw_deg });
    for (wheel, count) in [-c, c, -c, c].into_iter().enumerate() {
        s.ingest(at, SensorEvent::Encoder { wheel, count });
    }
    s.smooth_yaw(cfg, turning);
    s.estimate_imu_drift(at, cfg, turning);
}

#[test]
fn the_smoothed_yaw_averages_the_imu_noise_and_follows_the_wheels_at_once() {
    let cfg = without_drift();
    let mut s = SensorState::default();
    // 3 s at rest, 50 Hz: the IMU jitters ±0.2°, the wheels stand still. The filter starts
    // from the first sample (+0.2°), which has decayed after 2.4 s; what is left is the
    // jitter, 20 times smaller than the IMU's.
    for k in 0..150u64 {
        let noise = if k % 2 == 0 { 0.2 } else { -0.2 };
        feed(&mut s, &cfg, ms(20 * k), noise, 0.0, false);
        if k > 120 {
            let y = s.yaw_deg().unwrap().value;
            assert!(y.abs() < 0.01, "sample {k}: smoothed {y:.4}, raw {noise}");
        }
    }
    // the wheels turn the robot 2° in one sample and the IMU agrees: no lag
    let wheel = 2.0;
    let counts = f64::from(wheel_deg_to_counts(&cfg, wheel));
    let turned = counts / cfg.encoder_counts_per_metre() / cfg.rotation_lever_m();
    feed(&mut s, &cfg, ms(3000), turned.to_degrees() + 0.2, wheel, false);
    let y = s.yaw_deg().unwrap().value;
    assert!((y - turned.to_degrees()).abs() < 0.05, "smoothed {y:.3}, turned {:.3}", turned.to_degrees());
    // off: the raw IMU
    let mut raw = cfg.clone();
    raw.imu.smoothing = None;
    feed(&mut s, &raw, ms(3020), 1.0, wheel, false);
    assert!((s.yaw_deg().unwrap().value - 1.0).abs() < 1e-9);
}

fn wheel_deg_to_counts(cfg: &CartoConfig, deg: f64) -> i32 {
    (deg.to_radians() * cfg.encoder_counts_per_metre() * cfg.rotation_lever_m()).round() as i32
}

#[test]
fn the_smoothed_yaw_restarts_from_the_imu_on_a_slip_and_while_turning() {
    let cfg = without_drift();
    let mut s = SensorState::default();
    for k in 0..50u64 {
        feed(&mut s, &cfg, ms(20 * k), 0.0, 0.0, false);
    }
    // the wheels say 3° (they slipped), the IMU says the robot did not turn: the IMU wins
    feed(&mut s, &cfg, ms(1000), 0.1, 3.0, false);
    assert!((s.yaw_deg().unwrap().value - 0.1).abs() < 1e-9, "{:?}", s.yaw_deg());
    // while turning, each sample is the IMU's own
    feed(&mut s, &cfg, ms(1020), 5.0, 3.5, true);
    assert!((s.yaw_deg().unwrap().value - 5.0).abs() < 1e-9);
}

#[test]
fn the_drift_estimate_takes_no_sample_while_turning() {
    let cfg = CartoConfig::default();
    let (mut turning, mut still) = (SensorState::default(), SensorState::default());
    // 30 s: the IMU drifts 0.5°/min against wheels that stand still
    for k in 0..=300u64 {
        let yaw = -0.5 * (k as f64 * 0.1) / 60.0;
        feed(&mut turning, &cfg, ms(k * 100), yaw, 0.0, true);
        feed(&mut still, &cfg, ms(k * 100), yaw, 0.0, false);
    }
    assert_eq!(turning.imu_drift_deg(), 0.0);
    assert!((still.imu_drift_deg() + 0.25).abs() < 0.03, "{}", still.imu_drift_deg());
}

/// A robot whose wheels stand still (at rest, or slipping under a push) while the IMU reads
/// `yaws`, one sample every 100 ms, with the default configuration.
fn imu_over_still_wheels(yaws: impl IntoIterator<Item = f64>) -> SensorState {
    let cfg = CartoConfig::default();
    let mut s = SensorState::default();
    for (k, yaw) in (0u64..).zip(yaws) {
        feed(&mut s, &cfg, ms(100 * k), yaw, 0.0, false);
    }
    s
}

#[test]
fn a_body_turned_slowly_under_slipping_wheels_is_slip_not_drift() {
    // Generated flat seed 26 (issue 10): a robot pushed round by a leg turned 4° at under
    // 3°/s while its wheels slipped; the estimate, which only knew 10° jumps, followed the
    // gap at 3°/min and turned every later FORWARD off the grid by up to 6°.
    let s = imu_over_still_wheels(
        std::iter::repeat_n(0.0, 50)
            // 4° in 2 s (2°/s): every sample passes the rate check
            .chain((1..=20).map(|k| 0.2 * f64::from(k)))
            // then 2 minutes of straight driving with the body really at 4°
            .chain(std::iter::repeat_n(4.0, 1200)),
    );
    assert!(s.imu_drift_deg().abs() < 0.2, "estimate {:.2}° (the slip is 4°)", s.imu_drift_deg());
    assert!((s.yaw_deg().unwrap().value - 4.0).abs() < 0.2, "{:?}", s.yaw_deg());
}

/// Generated office seed 4 (issue 10): after each slip the estimate was re-anchored on the
/// last sample of the hold, and one sample may be off (the IMU's noise, the wheels' timing,
/// the end of the push); the drift estimate lost 0.2–1° at each of 25 slips, 7° in 48
/// minutes. The anchor is now the mean of the samples after the hold.
#[test]
fn a_slip_is_anchored_on_the_samples_after_it_not_on_one() {
    let s = imu_over_still_wheels(
        std::iter::repeat_n(0.0, 50)
            // a push turns the body 4° under slipping wheels, and 0.5° more for the last
            // 0.3 s of the 2 s hold (the first of those samples fails the rate check, the
            // others are taken)
            .chain((0..20).map(|k| if k >= 17 { 4.5 } else { 4.0 }))
            // then the body settles at 4° for 2 minutes of straight driving, the IMU jittering
            .chain((0..1200).map(|k| if k % 2 == 0 { 4.05 } else { 3.95 })),
    );
    assert_eq!(s.imu_drift_jumps(), 1);
    assert!(s.imu_drift_deg().abs() < 0.1, "estimate {:.2}° (no drift)", s.imu_drift_deg());
    assert!((s.yaw_deg().unwrap().value - 4.0).abs() < 0.1, "{:?}", s.yaw_deg());
}

#[test]
fn encoders_sampled_at_different_times_do_not_look_like_a_turn() {
    // Driving straight at 0.36 m/s with each encoder reporting 50 ms after the one before,
    // stopping and driving on: the raw counts differ by 1.8 cm between wheels while the robot
    // drives and agree at rest, so with raw counts the gap jumps by 2–3° at every start and
    // stop. Taken at the IMU sample's time the counts agree, and nothing jumps.
    let cfg = CartoConfig::default();
    let mut s = SensorState::default();
    let cps = 0.36 * cfg.encoder_counts_per_metre();
    let mut count = 0.0;
    let mut seen_apart = false;
    for k in 0..=1200u64 {
        let now = ms(k * 50);
        let driving = (k / 200) % 2 == 0; // 10 s driving, 10 s at rest, ...
        if driving {
            count += cps * 0.05;
        }
        s.ingest(now, SensorEvent::Encoder { wheel: (k % 4) as usize, count: count.round() as i32 });
        if k % 2 == 0 {
            s.ingest(now, SensorEvent::Heading { cw_deg: 0.0 });
            s.smooth_yaw(&cfg, false);
            s.estimate_imu_drift(now, &cfg, false);
        }
        let raw = s.counts().map(|c| c.value).unwrap_or_default();
        seen_apart |= raw.iter().max().zip(raw.iter().min()).is_some_and(|(a, b)| a - b > 10);
    }
    assert!(seen_apart, "the raw counts should disagree while driving");
    assert_eq!(s.imu_drift_jumps(), 0);
    assert!(s.imu_drift_deg().abs() < 0.1, "estimate {:.3}°", s.imu_drift_deg());
}

#[test]
fn wrap180_stays_in_half_open_range() {
    assert_eq!(wrap180(190.0), -170.0);
    assert_eq!(wrap180(-190.0), 170.0);
    assert_eq!(wrap180(180.0), 180.0);
    assert_eq!(wrap180(-180.0), 180.0);
    assert_eq!(wrap180(720.0 + 5.0), 5.0);
}

#[test]
fn yaw_unwraps_across_north_and_turns_clockwise_into_negative() {
    let mut s = SensorState::default();
    s.ingest(ms(0), SensorEvent::Heading { cw_deg: 10.0 });
    assert_eq!(s.yaw_deg().unwrap().value, -10.0);
    s.ingest(ms(100), SensorEvent::Heading { cw_deg: 350.0 });
    assert!((s.yaw_deg().unwrap().value - 10.0).abs() < 1e-9);
    s.ingest(ms(200), SensorEvent::Heading { cw_deg: 100.0 });
    assert!((s.yaw_deg().unwrap().value - (-100.0)).abs() < 1e-9);
}

#[test]
fn counts_need_all_four_wheels_and_extrapolate_from_the_last_two() {
    let cfg = CartoConfig::default();
    let mut s = SensorState::default();
    for w in 0..3 {
        s.ingest(ms(0), SensorEvent::Encoder { wheel: w, count: 0 });
    }
    assert!(s.counts().is_none());
    s.ingest(ms(0), SensorEvent::Encoder { wheel: 3, count: 0 });
    for w in 0..4 {
        s.ingest(ms(200), SensorEvent::Encoder { wheel: w, count: 100 });
    }
    // 100 counts in 200 ms = 500 counts/s; 100 ms later, 50 more.
    let p = s.predicted_counts(ms(300), &cfg).unwrap();
    assert!(p.iter().all(|c| (c - 150.0).abs() < 1e-6), "{p:?}");
    // extrapolation is capped
    let p = s.predicted_counts(ms(5000), &cfg).unwrap();
    assert!(p.iter().all(|c| (c - 250.0).abs() < 1e-6), "{p:?}");
}

/// Sensors with all four encoders at 0 at time 0 and nothing else.
fn encoders_at_zero() -> SensorState {
    let mut s = SensorState::default();
    for w in 0..4 {
        s.ingest(ms(0), SensorEvent::Encoder { wheel: w, count: 0 });
    }
    s
}

#[test]
fn fresh_telemetry_wins_over_encoder_differences() {
    let cfg = CartoConfig::default();
    let mut s = encoders_at_zero();
    s.ingest(ms(50), SensorEvent::WheelRpm { rpm: [60.0; 4] });
    let rate = s.wheel_rate_cps(0, ms(100), &cfg);
    assert!((rate - cfg.chassis.encoder_counts_per_wheel_rev).abs() < 1e-6);
    // stale telemetry is ignored
    assert_eq!(s.wheel_rate_cps(0, ms(1000), &cfg), 0.0);
    // pure rotation: FR/RR forward, FL/RL backward → counter-clockwise
    s.ingest(ms(1000), SensorEvent::WheelRpm { rpm: [-60.0, 60.0, -60.0, 60.0] });
    assert!(s.yaw_rate_dps(ms(1000), &cfg) > 0.0);
}

#[test]
fn telemetry_faster_than_the_motors_can_turn_is_not_used() {
    // lossy-motor seed 16: a frame with two corrupted bytes passed the one-byte checksum
    // and carried the odometry 75 m back in one extrapolation
    let cfg = CartoConfig::default();
    let mut s = encoders_at_zero();
    let top = cfg.chassis.max_wheel_rpm as f32;
    s.ingest(ms(50), SensorEvent::WheelRpm { rpm: [60.0, 60.0, -1.0e6, 60.0] });
    assert_eq!(s.wheel_rate_cps(0, ms(100), &cfg), 0.0, "the encoders' rate (none yet) is used");
    assert_eq!(s.yaw_rate_dps(ms(100), &cfg), 0.0);
    // the motors at full speed, or pushed a little past it, are believed
    s.ingest(ms(100), SensorEvent::WheelRpm { rpm: [1.5 * top; 4] });
    assert!(s.wheel_rate_cps(0, ms(120), &cfg) > 0.0);
}

#[test]
fn line_timer_gives_queued_frames_the_burst_start() {
    let mut t = LineTimer::new(9600); // 1041.7 µs per byte
    // A 10-byte frame completes at 110 ms: it started at ~99.58 ms.
    let a = t.sampled_at(Instant::from_micros(110_000), 10);
    assert_eq!(a, Instant::from_micros(110_000 - 10_417));
    // A 42-byte frame queued right behind it completes 43.75 ms later: same burst.
    let b = t.sampled_at(Instant::from_micros(110_000 + 43_750), 42);
    assert_eq!(b, a);
    // After a pause, a new burst starts at its own start.
    let c = t.sampled_at(Instant::from_micros(300_000), 11);
    assert_eq!(c, Instant::from_micros(300_000 - 11_458));
    // No correction without a baud rate.
    assert_eq!(LineTimer::new(0).sampled_at(Instant::from_millis(5), 40), Instant::from_millis(5));
}

#[test]
fn keep_state_sends_at_2hz_with_wrapping_sequence_and_detects_loss() {
    let mut k = KeepState::new(Duration::from_millis(500), Duration::from_millis(1500));
    assert_eq!(k.poll(ms(0)), (Some(1), None));
    assert_eq!(k.poll(ms(499)), (None, None));
    assert_eq!(k.poll(ms(500)), (Some(2), None));
    k.heard(ms(600));
    assert_eq!(k.poll(ms(2099)).1, None);
    assert_eq!(k.poll(ms(2100)).1, Some(PeerEvent::Lost));
    assert_eq!(k.poll(ms(2200)).1, None, "loss is reported once");
    assert_eq!(k.heard(ms(2300)), Some(PeerEvent::Back));
    k.next_seq = u16::MAX;
    let (a, _) = k.poll(ms(10_000));
    let (b, _) = k.poll(ms(10_500));
    assert_eq!((a, b), (Some(u16::MAX), Some(0)));
}

#[test]
fn silent_board_from_the_start_is_lost_after_the_timeout() {
    let mut k = KeepState::new(Duration::from_millis(500), Duration::from_millis(1500));
    assert_eq!(k.poll(ms(100)).1, None);
    assert_eq!(k.poll(ms(1600)).1, Some(PeerEvent::Lost));
}

/// The default configuration without the IMU drift estimate.
fn without_drift() -> CartoConfig {
    let mut cfg = CartoConfig::default();
    cfg.imu.drift = None;
    cfg
}
