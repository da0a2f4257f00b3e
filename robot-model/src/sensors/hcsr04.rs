//! HC-SR04 ultrasonic ranger.
//!
//! The simulator casts [`HcSr04::ray_count`] rays across the cone from the sensor's mount and
//! hands in what each ray hit. [`HcSr04::echo`] then applies, in order:
//! 1. specular loss: a hit whose incidence (angle from the surface normal) exceeds the limit
//!    sends no echo back;
//! 2. the nearest surviving hit wins;
//! 3. Gaussian noise (σ from the profile) on the distance, in centimetres;
//! 4. echo-time quantisation: the echo is timed in whole microseconds, then divided by 58
//!    (`cm = round(cm·58) / 58`, a resolution of 1/58 cm ≈ 0.17 mm);
//! 5. the range window: results outside `[min_cm, max_cm]` are "no echo".
//!
//! Invariants: each call to `echo`/`measure` draws exactly one normal sample from the RNG,
//! whatever the hits, so the RNG stream does not depend on the scene; a returned distance is
//! always a multiple of 1/58 cm within the window.

use rand::Rng;
use rand_distr::StandardNormal;

use crate::pose::Pose2;
use crate::profile::{RobotProfile, SonarParams};
use crate::time::{Duration, Instant};

/// What one ray of the sonar cone hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Distance from the sensor to the hit point, metres.
    pub distance_m: f32,
    /// Angle between the ray and the surface normal, radians (0 = head-on; sign ignored).
    pub incidence_rad: f32,
}

/// Microseconds of echo time per centimetre of distance (datasheet: `µs / 58 = cm`).
pub const ECHO_US_PER_CM: f32 = 58.0;

/// The HC-SR04 model: echo rule, measurement cycle and latest result.
#[derive(Debug, Clone, PartialEq)]
pub struct HcSr04 {
    params: SonarParams,
    cycle: Duration,
    next_due: Option<Instant>,
    latest: Option<f32>,
    measurements: u64,
}

impl HcSr04 {
    /// A sensor with the given parameters, due immediately.
    pub fn new(params: SonarParams) -> Self {
        let cycle = Duration::from_millis(u64::from(params.cycle_ms));
        HcSr04 { params, cycle, next_due: None, latest: None, measurements: 0 }
    }

    /// A sensor with the profile's sonar parameters.
    pub fn from_profile(p: &RobotProfile) -> Self {
        Self::new(p.sonar.clone())
    }

    /// The parameters in use.
    pub fn params(&self) -> &SonarParams {
        &self.params
    }

    /// The sensor's pose in the body frame (x forward, y left, heading CCW).
    pub fn mount(&self) -> Pose2 {
        Pose2::new(self.params.mount_x_m, self.params.mount_y_m, self.params.mount_heading_deg.to_radians())
    }

    /// Number of rays the caller should cast.
    pub fn ray_count(&self) -> usize {
        self.params.rays as usize
    }

    /// Ray directions relative to the sensor axis, radians CCW, evenly spread across the cone
    /// from `-cone/2` to `+cone/2` (a single ray points along the axis).
    pub fn ray_angles(&self) -> Vec<f32> {
        let n = self.ray_count();
        let half = self.params.cone_deg.to_radians() / 2.0;
        if n <= 1 {
            return vec![0.0; n];
        }
        (0..n).map(|i| -half + 2.0 * half * i as f32 / (n - 1) as f32).collect()
    }

    /// Longest distance worth casting a ray for, metres.
    pub fn max_range_m(&self) -> f32 {
        self.params.max_cm / 100.0
    }

    /// Whether a new measurement cycle is due at `now`.
    pub fn due(&self, now: Instant) -> bool {
        self.next_due.is_none_or(|t| now >= t)
    }

    /// Measures now: computes the echo, stores it as the latest result and starts a new cycle.
    pub fn measure(&mut self, now: Instant, hits: &[Option<RayHit>], rng: &mut impl Rng) -> Option<f32> {
        let r = self.echo(hits, rng);
        self.latest = r;
        self.measurements += 1;
        self.next_due = Some(now + self.cycle);
        r
    }

    /// The latest measured distance in cm, `None` for no echo (or no measurement yet).
    pub fn latest(&self) -> Option<f32> {
        self.latest
    }

    /// Number of measurements taken.
    pub fn measurements(&self) -> u64 {
        self.measurements
    }

    /// Which of `hits` an echo would come from: the nearest within the incidence limit (the
    /// first of equals); `None` when none is.
    pub fn nearest_audible(&self, hits: &[Option<RayHit>]) -> Option<usize> {
        let limit = self.params.incidence_limit_deg.to_radians();
        let mut nearest: Option<(usize, f32)> = None;
        for (i, h) in hits.iter().enumerate() {
            if let Some(h) = h
                && h.distance_m.is_finite()
                && h.distance_m >= 0.0
                && h.incidence_rad.abs() <= limit
                && nearest.is_none_or(|(_, d)| h.distance_m < d)
            {
                nearest = Some((i, h.distance_m));
            }
        }
        nearest.map(|(i, _)| i)
    }

    /// The echo rule alone (see the module docs): hits → distance in cm or no echo.
    pub fn echo(&self, hits: &[Option<RayHit>], rng: &mut impl Rng) -> Option<f32> {
        let z: f32 = rng.sample(StandardNormal);
        let nearest = hits.get(self.nearest_audible(hits)?).copied().flatten()?.distance_m;
        let cm = nearest * 100.0 + z * self.params.noise_sigma_cm;
        let echo_us = (cm * ECHO_US_PER_CM).round();
        let cm = echo_us / ECHO_US_PER_CM;
        (cm.is_finite() && cm >= self.params.min_cm && cm <= self.params.max_cm).then_some(cm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn noiseless() -> HcSr04 {
        let mut p = RobotProfile::default().sonar;
        p.noise_sigma_cm = 0.0;
        HcSr04::new(p)
    }

    fn hit(d: f32, inc_deg: f32) -> Option<RayHit> {
        Some(RayHit { distance_m: d, incidence_rad: inc_deg.to_radians() })
    }

    #[test]
    fn nearest_surviving_echo_wins() {
        let s = noiseless();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        // 0.40 m is nearer but hits at 40° incidence: lost. 0.80 m at 10° survives.
        assert_eq!(s.echo(&[hit(0.40, 40.0), hit(0.80, 10.0), hit(1.2, 0.0), None], &mut rng), Some(80.0));
        assert_eq!(s.echo(&[hit(0.80, 10.0), hit(0.30, -22.5)], &mut rng), Some(30.0));
        assert_eq!(s.echo(&[hit(0.40, 22.6), None], &mut rng), None);
        assert_eq!(s.echo(&[None, None], &mut rng), None);
        // which hit the echo comes from
        assert_eq!(s.nearest_audible(&[hit(0.40, 40.0), hit(0.80, 10.0), hit(1.2, 0.0), None]), Some(1));
        assert_eq!(s.nearest_audible(&[hit(0.80, 10.0), hit(0.30, -22.5)]), Some(1));
        assert_eq!(s.nearest_audible(&[hit(0.40, 22.6), None]), None);
    }

    #[test]
    fn window_is_2_to_400_cm() {
        let s = noiseless();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        assert_eq!(s.echo(&[hit(0.019, 0.0)], &mut rng), None);
        assert_eq!(s.echo(&[hit(0.02, 0.0)], &mut rng), Some(2.0));
        assert_eq!(s.echo(&[hit(4.0, 0.0)], &mut rng), Some(400.0));
        assert_eq!(s.echo(&[hit(4.01, 0.0)], &mut rng), None);
    }

    #[test]
    fn echo_time_is_quantised_to_whole_microseconds() {
        let s = noiseless();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        // 123.4567 cm → 7160.49 µs → 7160 µs → 123.448 cm
        let cm = s.echo(&[hit(1.234_567, 0.0)], &mut rng).unwrap();
        assert_eq!(cm, 7160.0 / 58.0);
    }

    #[test]
    fn noise_is_seeded_and_has_the_profile_sigma() {
        let s = HcSr04::from_profile(&RobotProfile::default()); // σ = 0.3 cm
        let run = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            (0..2000).map(|_| s.echo(&[hit(1.0, 0.0)], &mut rng).unwrap()).collect::<Vec<_>>()
        };
        let a = run(3);
        assert_eq!(a, run(3));
        assert_ne!(a, run(4));
        let mean = a.iter().sum::<f32>() / a.len() as f32;
        let var = a.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / a.len() as f32;
        assert!((mean - 100.0).abs() < 0.05, "mean {mean}");
        assert!((var.sqrt() - 0.3).abs() < 0.03, "sigma {}", var.sqrt());
    }

    #[test]
    fn rng_draws_do_not_depend_on_the_scene() {
        let s = HcSr04::from_profile(&RobotProfile::default());
        let mut a = ChaCha8Rng::seed_from_u64(9);
        let mut b = ChaCha8Rng::seed_from_u64(9);
        s.echo(&[None], &mut a);
        s.echo(&[hit(1.0, 0.0), hit(2.0, 0.0)], &mut b);
        assert_eq!(a.random::<u64>(), b.random::<u64>());
    }

    #[test]
    fn measurement_cycle_is_60_ms() {
        let mut s = noiseless();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        assert!(s.due(Instant::ZERO));
        assert_eq!(s.measure(Instant::ZERO, &[hit(0.5, 0.0)], &mut rng), Some(50.0));
        assert!(!s.due(Instant::from_millis(59)));
        assert!(s.due(Instant::from_millis(60)));
        assert_eq!(s.latest(), Some(50.0));
        s.measure(Instant::from_millis(60), &[None], &mut rng);
        assert_eq!(s.latest(), None);
        assert_eq!(s.measurements(), 2);
    }

    #[test]
    fn rays_span_the_cone() {
        let s = noiseless();
        let a = s.ray_angles();
        assert_eq!(a.len(), 5);
        assert!((a[0] + 7.5f32.to_radians()).abs() < 1e-6 && (a[4] - 7.5f32.to_radians()).abs() < 1e-6);
        assert!(a[2].abs() < 1e-6);
        assert_eq!(s.mount(), Pose2::new(0.13, 0.0, 0.0));
    }
}
