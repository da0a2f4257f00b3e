//! The checks a single value of a scenario must pass, run by serde while it reads the value
//! (`#[serde(deserialize_with = …)]`), so the error points at the value itself.
//!
//! Each function reads the plain type (`f32`, `(f32, f32)`, …) and refuses a bad one with a
//! short message; [`super::source::parse`] puts the value's path in front (`obstacles[2].radius:
//! must be a positive number of metres`) and its line and column. The scenario's types stay
//! plain numbers. Checks that need two values or the robot profile are in
//! [`crate::setup::RunSetup`].

use rapier2d::parry::math::Vector;
use rapier2d::parry::shape::ConvexPolygon;
use serde::de::{Deserialize, Deserializer, Error};

use super::Obstacle;

/// Reads a `T` and keeps it when `ok(&value)`, else fails with `message`.
fn checked<'de, T, D>(d: D, ok: impl FnOnce(&T) -> bool, message: &str) -> Result<T, D::Error>
where
    T: Deserialize<'de>,
    D: Deserializer<'de>,
{
    let value = T::deserialize(d)?;
    if ok(&value) { Ok(value) } else { Err(D::Error::custom(message)) }
}

/// Largest coordinate or length a scenario may hold, metres: far beyond any room the link
/// protocol's one-byte cells can address, small enough to catch a typo such as 4294967296.
pub const MAX_COORD_M: f32 = 1000.0;

fn finite2(p: &(f32, f32)) -> bool {
    in_range(p.0) && in_range(p.1)
}

fn in_range(v: f32) -> bool {
    v.is_finite() && v.abs() <= MAX_COORD_M
}

fn positive(v: f32) -> bool {
    v.is_finite() && v > 0.0
}

fn positive_m(v: f32) -> bool {
    in_range(v) && v > 0.0
}

/// Signed area of a polygon (positive when counter-clockwise).
pub fn polygon_area(points: &[(f32, f32)]) -> f32 {
    let n = points.len();
    let mut twice = 0.0;
    for i in 0..n {
        let (x0, y0) = points[i];
        let (x1, y1) = points[(i + 1) % n];
        twice += x0 * y1 - x1 * y0;
    }
    twice * 0.5
}

/// A scenario name: the output folder `runs/NAME`.
pub fn name<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    checked(
        d,
        |n: &String| !n.is_empty() && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_'),
        "name must be non-empty ASCII letters, digits, '-' or '_'",
    )
}

/// The room: a polygon of at least 3 finite corners with an area.
pub fn room<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<(f32, f32)>, D::Error> {
    let room = Vec::<(f32, f32)>::deserialize(d)?;
    if room.len() < 3 {
        return Err(D::Error::custom("room needs at least 3 corners"));
    }
    if !room.iter().all(finite2) {
        return Err(D::Error::custom("room corners must be finite numbers within ±1000 m"));
    }
    if polygon_area(&room).abs() < 1e-6 {
        return Err(D::Error::custom("room polygon has no area"));
    }
    Ok(room)
}

/// A grid cell size, metres.
pub fn cell<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
    checked(
        d,
        |c: &Option<f32>| c.is_none_or(|c| c.is_finite() && (0.05..=5.0).contains(&c)),
        "cell must be between 0.05 and 5 metres",
    )
}

/// The physics step, milliseconds.
pub fn step_ms<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    checked(
        d,
        |v: &f32| v.is_finite() && (0.1..=50.0).contains(v),
        "physics step_ms must be between 0.1 and 50",
    )
}

/// A point, metres.
pub fn point<'de, D: Deserializer<'de>>(d: D) -> Result<(f32, f32), D::Error> {
    checked(d, finite2, "a point is two finite numbers within ±1000 m (metres)")
}

/// A width and a height, metres.
pub fn size<'de, D: Deserializer<'de>>(d: D) -> Result<(f32, f32), D::Error> {
    checked(
        d,
        |s: &(f32, f32)| positive_m(s.0) && positive_m(s.1),
        "a size is two positive numbers up to 1000 (metres)",
    )
}

/// A length, metres.
pub fn length<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    checked(d, |v: &f32| positive_m(*v), "a length is a positive number of metres, up to 1000")
}

/// Any finite number (an angle).
pub fn finite<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    checked(d, |v: &f32| v.is_finite(), "must be a finite number")
}

/// The corners of a convex obstacle: finite, and not all on one line (else there is no hull).
pub fn convex_points<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<(f32, f32)>, D::Error> {
    checked(
        d,
        |points: &Vec<(f32, f32)>| {
            let pts: Vec<Vector> = points.iter().map(|&(x, y)| Vector::new(x, y)).collect();
            points.iter().all(finite2) && ConvexPolygon::from_convex_hull(&pts).is_some()
        },
        "a polygon needs finite corners within ±1000 m that do not all lie on one line",
    )
}

/// A positive time limit, seconds (`f32`).
pub fn positive_s<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    checked(d, |v: &f32| positive(*v), "must be a positive number of seconds")
}

/// A time from now or from the start, seconds: zero or more.
pub fn non_negative_s<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    checked(d, |v: &f32| v.is_finite() && *v >= 0.0, "must be zero or a positive number of seconds")
}

/// An optional positive time limit, seconds (`f64`).
pub fn optional_positive_s<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    checked(
        d,
        |v: &Option<f64>| v.is_none_or(|v| v.is_finite() && v > 0.0),
        "must be a positive number of seconds",
    )
}

/// A probability.
pub fn rate<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    checked(d, |v: &f64| (0.0..=1.0).contains(v), "link fault rates must be between 0 and 1")
}

/// An optional fraction (0 to 1).
pub fn fraction<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    checked(d, |v: &Option<f64>| v.is_none_or(|v| (0.0..=1.0).contains(&v)), "fractions are between 0 and 1")
}

/// A latency, milliseconds: zero or more.
pub fn latency_ms<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    checked(d, |v: &f32| v.is_finite() && *v >= 0.0, "latency_ms must be zero or positive")
}

impl Obstacle {
    /// A box around the obstacle (min x, min y, max x, max y), metres; a rotated box's is
    /// the box around its circumscribed circle.
    pub fn bounds(&self) -> (f32, f32, f32, f32) {
        match self {
            Obstacle::Box { center: (x, y), size: (w, h), .. } => {
                let r = 0.5 * w.hypot(*h);
                (x - r, y - r, x + r, y + r)
            }
            Obstacle::Circle { center: (x, y), radius: r } => (x - r, y - r, x + r, y + r),
            Obstacle::Segment { from, to } => bounds(&[*from, *to]),
            Obstacle::Polygon { points } => bounds(points),
        }
    }
}

/// The box around `points` (min x, min y, max x, max y).
pub fn bounds(points: &[(f32, f32)]) -> (f32, f32, f32, f32) {
    points.iter().fold((f32::MAX, f32::MAX, f32::MIN, f32::MIN), |b, &(x, y)| {
        (b.0.min(x), b.1.min(y), b.2.max(x), b.3.max(y))
    })
}
