//! Sensor models as plain structs: the HC-SR04 ultrasonic ranger, the IMU heading and the
//! wheel encoders. They turn true physical quantities (ray hits, heading, wheel angle) into what
//! the real part would report. Randomness always comes from the caller's seeded RNG
//! (`&mut impl rand::Rng`), so a run is reproducible from its seed.
//!
//! ```
//! use rand::SeedableRng;
//! use robot_model::profile::RobotProfile;
//! use robot_model::sensors::{Encoder, HcSr04, Imu, RayHit};
//! use robot_model::time::Instant;
//!
//! let profile = RobotProfile::default();
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
//!
//! let mut sonar = HcSr04::from_profile(&profile);
//! let hits = [None, Some(RayHit { distance_m: 0.5, incidence_rad: 0.1 }), None, None, None];
//! let cm = sonar.measure(Instant::ZERO, &hits, &mut rng).unwrap();
//! assert!((cm - 50.0).abs() < 2.0);
//!
//! let imu = Imu::from_profile(&profile);
//! let deg = imu.read(Instant::ZERO, core::f32::consts::FRAC_PI_2, &mut rng); // facing +y (CCW 90°)
//! assert!((deg - 270.0).abs() < 1.5); // NavX heading is clockwise
//!
//! let mut enc = Encoder::from_profile(&profile);
//! assert_eq!(enc.update(core::f64::consts::TAU), 206); // one wheel turn = 206.8 pulses
//! ```

mod encoder;
mod hcsr04;
mod imu;

pub use encoder::Encoder;
pub use hcsr04::{HcSr04, RayHit};
pub use imu::Imu;
