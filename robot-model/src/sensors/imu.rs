//! IMU heading, as the NavX reports it: fused heading in degrees, `[0, 360)`, **clockwise**.
//!
//! The world heading `θ` is counter-clockwise (see [`crate::pose`]), so the reading is
//! `wrap₃₆₀(−deg(θ − θ₀) + drift·minutes(now − t₀) + σ·z)`, where `θ₀`, `t₀` are set by
//! [`Imu::zero`] (initially `θ₀ = 0`, i.e. 0° faces world `+x`, and `t₀` = run start). Zeroing
//! also restarts the drift, as re-zeroing a gyro does.
//!
//! Invariant: every [`Imu::read`] draws exactly one normal sample from the RNG.

use rand::Rng;
use rand_distr::StandardNormal;

use crate::pose::wrap_degrees_360;
use crate::profile::{ImuParams, RobotProfile};
use crate::time::Instant;

/// The IMU heading model.
#[derive(Debug, Clone, PartialEq)]
pub struct Imu {
    params: ImuParams,
    zero_heading_rad: f32,
    zero_time: Instant,
}

impl Imu {
    /// An IMU with the given noise and drift, zeroed at heading 0 at the run start.
    pub fn new(params: ImuParams) -> Self {
        Imu { params, zero_heading_rad: 0.0, zero_time: Instant::ZERO }
    }

    /// An IMU with the profile's parameters.
    pub fn from_profile(p: &RobotProfile) -> Self {
        Self::new(p.imu.clone())
    }

    /// Makes the current true heading read 0° from `now` on, and restarts the drift.
    pub fn zero(&mut self, now: Instant, true_heading_rad: f32) {
        self.zero_heading_rad = true_heading_rad;
        self.zero_time = now;
    }

    /// The reading without noise (true heading plus drift), degrees clockwise in `[0, 360)`.
    pub fn ideal(&self, now: Instant, true_heading_rad: f32) -> f32 {
        self.reading(now, true_heading_rad, 0.0)
    }

    /// A noisy reading, degrees clockwise in `[0, 360)`.
    pub fn read(&self, now: Instant, true_heading_rad: f32, rng: &mut impl Rng) -> f32 {
        let z: f32 = rng.sample(StandardNormal);
        self.reading(now, true_heading_rad, z * self.params.noise_sigma_deg)
    }

    fn reading(&self, now: Instant, true_heading_rad: f32, noise_deg: f32) -> f32 {
        let minutes = (now.saturating_since(self.zero_time).as_secs_f64() / 60.0) as f32;
        let rel = (true_heading_rad - self.zero_heading_rad).to_degrees();
        let deg = -rel + self.params.drift_deg_per_min * minutes + noise_deg;
        if deg.is_finite() { wrap_degrees_360(deg) } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::FRAC_PI_2;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn ideal_imu() -> Imu {
        Imu::new(ImuParams { noise_sigma_deg: 0.0, drift_deg_per_min: 0.0 })
    }

    #[test]
    fn heading_is_clockwise_degrees() {
        let imu = ideal_imu();
        assert!((imu.ideal(Instant::ZERO, FRAC_PI_2) - 270.0).abs() < 1e-3); // turned left 90°
        assert!((imu.ideal(Instant::ZERO, -FRAC_PI_2) - 90.0).abs() < 1e-3); // turned right 90°
        assert_eq!(imu.ideal(Instant::ZERO, 0.0), 0.0);
    }

    #[test]
    fn zero_makes_the_current_heading_read_zero() {
        let mut imu = ideal_imu();
        imu.zero(Instant::from_millis(10), 1.0);
        assert!(imu.ideal(Instant::from_millis(20), 1.0) < 1e-3);
        let right = imu.ideal(Instant::from_millis(20), 1.0 - FRAC_PI_2);
        assert!((right - 90.0).abs() < 1e-3, "{right}");
    }

    #[test]
    fn drift_is_linear_per_minute() {
        let mut imu = Imu::new(ImuParams { noise_sigma_deg: 0.0, drift_deg_per_min: 0.5 });
        assert!((imu.ideal(Instant::from_secs_f64(120.0), 0.0) - 1.0).abs() < 1e-4);
        imu.zero(Instant::from_secs_f64(120.0), 0.0);
        assert!((imu.ideal(Instant::from_secs_f64(180.0), 0.0) - 0.5).abs() < 1e-4);
    }

    #[test]
    fn noise_is_seeded_with_profile_sigma() {
        let imu = Imu::new(ImuParams { noise_sigma_deg: 0.2, drift_deg_per_min: 0.0 });
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let v: Vec<f32> = (0..4000)
            .map(|_| {
                let d = imu.read(Instant::ZERO, 0.5, &mut rng); // ≈ 331.35°
                d - wrap_degrees_360(-0.5f32.to_degrees())
            })
            .collect();
        let mean = v.iter().sum::<f32>() / v.len() as f32;
        let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / v.len() as f32).sqrt();
        assert!(mean.abs() < 0.02 && (sd - 0.2).abs() < 0.02, "mean {mean} sd {sd}");
    }
}
