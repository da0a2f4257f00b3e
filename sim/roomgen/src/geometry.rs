//! Geometry helpers: points, boxes and discs, and parry shapes to test clearances.

use super::*;

pub(super) type Pt = (f32, f32);

pub(super) fn add(a: Pt, b: Pt) -> Pt {
    (a.0 + b.0, a.1 + b.1)
}

pub(super) fn sub(a: Pt, b: Pt) -> Pt {
    (a.0 - b.0, a.1 - b.1)
}

pub(super) fn scale(a: Pt, k: f32) -> Pt {
    (a.0 * k, a.1 * k)
}

pub(super) fn length(a: Pt) -> f32 {
    a.0.hypot(a.1)
}

pub(super) fn unit(a: Pt) -> Pt {
    let l = length(a);
    if l > 0.0 { scale(a, 1.0 / l) } else { (1.0, 0.0) }
}

/// `a` turned 90° counter-clockwise.
pub(super) fn left(a: Pt) -> Pt {
    (-a.1, a.0)
}

pub(super) fn dir_deg(a: Pt) -> f32 {
    a.1.atan2(a.0).to_degrees()
}

/// The world point at `l` in the frame at `origin` turned `angle_deg`.
pub(super) fn local(origin: Pt, angle_deg: f32, l: Pt) -> Pt {
    let (s, c) = angle_deg.to_radians().sin_cos();
    (origin.0 + c * l.0 - s * l.1, origin.1 + s * l.0 + c * l.1)
}

/// Rounds to the millimetre (and turns −0 into 0).
pub(super) fn mm(v: f32) -> f32 {
    (v * 1000.0).round() / 1000.0 + 0.0
}

/// Rounds to a tenth of a degree, in (−180, 180].
pub(super) fn tenth(v: f32) -> f32 {
    let mut a = v % 360.0;
    if a <= -180.0 {
        a += 360.0;
    } else if a > 180.0 {
        a -= 360.0;
    }
    let a = (a * 10.0).round() / 10.0 + 0.0;
    if a <= -180.0 { 180.0 } else { a }
}

/// A box; its angle is written in (−90°, 90°], as a box turned by 180° is the same box.
pub(super) fn rect(center: Pt, size: Pt, angle_deg: f32) -> Obstacle {
    let mut angle = tenth(angle_deg);
    if angle > 90.0 {
        angle -= 180.0;
    } else if angle <= -90.0 {
        angle += 180.0;
    }
    Obstacle::Box {
        center: (mm(center.0), mm(center.1)),
        size: (mm(size.0).max(0.001), mm(size.1).max(0.001)),
        angle_deg: tenth(angle),
    }
}

pub(super) fn disc(center: Pt, radius: f32) -> Obstacle {
    Obstacle::Circle { center: (mm(center.0), mm(center.1)), radius: mm(radius).max(0.001) }
}

pub(super) fn uniform(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    if hi > lo { rng.random_range(lo..hi) } else { lo }
}

pub(super) fn chance(rng: &mut ChaCha8Rng, p: f64) -> bool {
    rng.random_bool(p.clamp(0.0, 1.0))
}

pub(super) fn sign(rng: &mut ChaCha8Rng) -> f32 {
    if chance(rng, 0.5) { 1.0 } else { -1.0 }
}

pub(super) fn pick<T: Copy>(rng: &mut ChaCha8Rng, items: &[T]) -> Option<T> {
    if items.is_empty() { None } else { Some(items[rng.random_range(0..items.len())]) }
}

/// The corners of a box obstacle, shrunk by `inset` on every side (its centre for a disc).
pub(super) fn corners(o: &Obstacle, inset: f32) -> Vec<Pt> {
    match o {
        Obstacle::Box { center, size, angle_deg } => {
            let (hw, hh) = ((size.0 * 0.5 - inset).max(0.0), (size.1 * 0.5 - inset).max(0.0));
            [(-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh)]
                .iter()
                .map(|&l| local(*center, *angle_deg, l))
                .collect()
        }
        Obstacle::Circle { center, .. } => vec![*center],
        Obstacle::Segment { from, to } => vec![*from, *to],
        Obstacle::Polygon { points } => points.clone(),
    }
}

pub(super) fn rect_outline(x0: f32, y0: f32, x1: f32, y1: f32) -> Vec<Pt> {
    vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
}

/// A parry shape with its placement and bounding box.
pub(super) struct Shaped {
    pub(super) pose: Pose,
    pub(super) shape: Box<dyn Shape>,
    pub(super) lo: Pt,
    pub(super) hi: Pt,
}

pub(super) fn shaped(o: &Obstacle) -> Option<Shaped> {
    let (pose, shape) = o.shape()?;
    let aabb = shape.compute_aabb(&pose);
    Some(Shaped { pose, shape, lo: (aabb.mins.x, aabb.mins.y), hi: (aabb.maxs.x, aabb.maxs.y) })
}

/// Whether `a` and `b` are closer than `margin` (touching counts; an untestable pair counts).
pub(super) fn near(a: &Shaped, b: &Shaped, margin: f32) -> bool {
    if a.lo.0 > b.hi.0 + margin
        || b.lo.0 > a.hi.0 + margin
        || a.lo.1 > b.hi.1 + margin
        || b.lo.1 > a.hi.1 + margin
    {
        return false;
    }
    if margin > 0.0 {
        query::distance(&a.pose, a.shape.as_ref(), &b.pose, b.shape.as_ref())
            .map_or(true, |d| d.distance < margin)
    } else {
        query::intersection_test(&a.pose, a.shape.as_ref(), &b.pose, b.shape.as_ref())
            .map_or(true, |i| i.intersecting)
    }
}
