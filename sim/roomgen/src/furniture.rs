//! Furniture placement: against walls or free-standing, with real sizes and any rotation.

use super::*;
use super::{draft::*, geometry::*, walls::*};

/// Puts a `width` × `depth` piece with its back to a random edge of `region`, `gap` from it;
/// `build(centre, angle)` makes the piece (local x along the wall, local +y into the room).
/// Returns the centre and angle used.
pub(super) fn against_wall(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    (width, depth): Pt,
    gap: Pt,
    build: &dyn Fn(Pt, f32) -> Item,
) -> Option<(Pt, f32)> {
    let n = region.len();
    let edges: Vec<usize> =
        (0..n).filter(|&i| length(sub(region[(i + 1) % n], region[i])) > width + 0.02).collect();
    for _ in 0..24 {
        let i = pick(rng, &edges)?;
        let (a, b) = (region[i], region[(i + 1) % n]);
        let (len, dir) = (length(sub(b, a)), unit(sub(b, a)));
        let t = uniform(rng, 0.005, len - width - 0.005);
        // Touching counts as overlapping: keep at least 2 mm.
        let g = uniform(rng, gap.0.max(0.002), gap.1);
        let center = add(add(a, scale(dir, t + width * 0.5)), scale(left(dir), g + depth * 0.5));
        let angle = tenth(dir_deg(dir));
        if d.place(build(center, angle), Some(region)) {
            return Some((center, angle));
        }
    }
    None
}

/// Puts a piece anywhere in `region`, turned by `angle(rng)`.
pub(super) fn free_standing(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    angle: &dyn Fn(&mut ChaCha8Rng) -> f32,
    build: &dyn Fn(Pt, f32) -> Item,
) -> Option<(Pt, f32)> {
    let aabb = grid::room_aabb(region);
    let (x0, y0, x1, y1) = (aabb.mins.x, aabb.mins.y, aabb.maxs.x, aabb.maxs.y);
    for _ in 0..24 {
        let center = (uniform(rng, x0, x1), uniform(rng, y0, y1));
        if !grid::point_in_polygon(region, center.0, center.1) {
            continue;
        }
        let a = tenth(angle(rng));
        if d.place(build(center, a), Some(region)) {
            return Some((center, a));
        }
    }
    None
}

/// Any angle at all.
pub(super) fn any_angle(rng: &mut ChaCha8Rng) -> f32 {
    uniform(rng, -180.0, 180.0)
}

/// Roughly square to the building: 0°, 90°, 180° or 270°, give or take 5°.
pub(super) fn squarish(rng: &mut ChaCha8Rng) -> f32 {
    let quarter = rng.random_range(0..4u8);
    f32::from(quarter) * 90.0 + uniform(rng, -5.0, 5.0)
}

/// Half the time square to the building, otherwise any angle.
pub(super) fn home_angle(rng: &mut ChaCha8Rng) -> f32 {
    if chance(rng, 0.5) { squarish(rng) } else { any_angle(rng) }
}

pub(super) fn chair_item(rng: &mut ChaCha8Rng, center: Pt, angle: f32) -> Item {
    let size = (0.45, mm(uniform(rng, 0.45, 0.55)));
    let leg = mm(uniform(rng, 0.02, 0.04));
    let inset = mm(uniform(rng, 0.01, 0.03));
    let legs = if chance(rng, 0.8) { Legs::Round { d: leg, inset } } else { Legs::Square { s: leg, inset } };
    let label = format!("chair {:.2} x {:.2} m, {}", size.0, size.1, legs.describe());
    Item::legged(label, Kind::Seat, center, size, angle, legs)
}

/// A chair at side `side` of a table (0: local −y, 1: +y, 2: −x, 3: +x), `along` metres from
/// the middle of that side, pushed in or pulled out, usually turned 10–45°.
#[allow(clippy::too_many_arguments)]
pub(super) fn chair_at(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    table: Pt,
    size: Pt,
    angle: f32,
    side: u8,
    along: f32,
) -> bool {
    for _ in 0..4 {
        let tuck = uniform(rng, -0.15, 0.25);
        let reach = |half: f32| half + 0.25 - tuck;
        let (l, face) = match side {
            0 => ((along, -reach(size.1 * 0.5)), 0.0),
            1 => ((along, reach(size.1 * 0.5)), 180.0),
            2 => ((-reach(size.0 * 0.5), along), -90.0),
            _ => ((reach(size.0 * 0.5), along), 90.0),
        };
        let turn =
            if chance(rng, 0.8) { sign(rng) * uniform(rng, 10.0, 45.0) } else { uniform(rng, -5.0, 5.0) };
        let item = chair_item(rng, local(table, angle, l), angle + face + turn);
        if d.place(item, Some(region)) {
            return true;
        }
    }
    false
}

/// A dining table (rectangular on four legs, or round on a pedestal) with `chairs` chairs.
pub(super) fn dining(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], chairs: usize) {
    if chance(rng, 0.3) {
        let diameter = mm(uniform(rng, 0.9, 1.2));
        let base = mm(uniform(rng, 0.4, 0.6));
        let build = |c: Pt, _a: f32| Item {
            label: format!("round table {diameter:.2} m on a pedestal {base:.2} m"),
            kind: Kind::Legged,
            footprint: disc(c, diameter * 0.5),
            parts: vec![disc(c, base * 0.5)],
            seals: false,
        };
        let Some((c, _)) = free_standing(rng, d, region, &any_angle, &build) else { return };
        for k in 0..chairs {
            let a = k as f32 * 360.0 / chairs as f32 + uniform(rng, -20.0, 20.0);
            chair_at(rng, d, region, c, (diameter, diameter), a, 0, 0.0);
        }
        return;
    }
    let size = (mm(uniform(rng, 1.2, 2.0)), mm(uniform(rng, 0.8, 1.0)));
    let legs = Legs::draw(rng, 0.04, 0.08, 0.0);
    let build = |c: Pt, a: f32| {
        let label = format!("dining table {:.2} x {:.2} m, {}", size.0, size.1, legs.describe());
        Item::legged(label, Kind::Legged, c, size, a, legs)
    };
    let Some((c, a)) = free_standing(rng, d, region, &home_angle, &build) else { return };
    for k in 0..chairs {
        let side = [0u8, 1, 0, 1, 2, 3][k % 6];
        let along = if side < 2 { uniform(rng, -0.35, 0.35) * size.0 } else { 0.0 };
        chair_at(rng, d, region, c, size, a, side, along);
    }
}

/// A desk against a wall with a chair in front of it (most of the time).
pub(super) fn desk_with_chair(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 1.0, 1.6)), mm(uniform(rng, 0.6, 0.8)));
    let legs = Legs::draw(rng, 0.03, 0.06, 0.4);
    let build = |c: Pt, a: f32| {
        let label = format!("desk {:.2} x {:.2} m, {}", size.0, size.1, legs.describe());
        Item::legged(label, Kind::Legged, c, size, a, legs)
    };
    if let Some((c, a)) = against_wall(rng, d, region, size, (0.0, 0.04), &build)
        && chance(rng, 0.85)
    {
        let along = uniform(rng, -0.25, 0.25);
        chair_at(rng, d, region, c, size, a, 1, along);
    }
}

/// Storage against a wall: a wardrobe, cabinet or shelf of real size.
pub(super) fn storage(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], deep: bool) {
    let (name, width, depth) = match rng.random_range(0..3u8) {
        0 if deep => ("wardrobe", uniform(rng, 0.8, 2.4), uniform(rng, 0.55, 0.65)),
        1 => ("cabinet", uniform(rng, 0.6, 1.6), uniform(rng, 0.4, 0.6)),
        _ => ("shelf", uniform(rng, 0.6, 2.0), uniform(rng, 0.35, 0.45)),
    };
    let size = (mm(width), mm(depth));
    let gap = if chance(rng, 0.7) { (0.0, 0.015) } else { (0.015, 0.06) };
    let build = |c: Pt, a: f32| {
        Item::solid(format!("{name} {:.2} x {:.2} m against a wall", size.0, size.1), c, size, a)
    };
    against_wall(rng, d, region, size, gap, &build);
}

/// A bin, plant pot or floor lamp.
pub(super) fn small_round(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let name = ["bin", "plant pot", "floor lamp"][rng.random_range(0..3usize)];
    let r = mm(uniform(rng, 0.1, 0.2));
    let build = |c: Pt, _a: f32| Item::round(format!("{name} {:.2} m across", 2.0 * r), c, r);
    free_standing(rng, d, region, &any_angle, &build);
}

pub(super) fn sofa(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 1.6, 2.4)), mm(uniform(rng, 0.8, 1.0)));
    let build = |c: Pt, a: f32| Item::solid(format!("sofa {:.2} x {:.2} m", size.0, size.1), c, size, a);
    if chance(rng, 0.6) {
        against_wall(rng, d, region, size, (0.0, 0.1), &build);
    } else {
        free_standing(rng, d, region, &home_angle, &build);
    }
}

pub(super) fn bed(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 0.9, 1.8)), mm(uniform(rng, 1.9, 2.1)));
    let build = |c: Pt, a: f32| {
        Item::solid(format!("bed {:.2} x {:.2} m, head to a wall", size.0, size.1), c, size, a)
    };
    against_wall(rng, d, region, size, (0.0, 0.03), &build);
}

pub(super) fn counter(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 1.2, 3.6)), 0.6);
    let build = |c: Pt, a: f32| Item::solid(format!("kitchen counter {:.2} x 0.60 m", size.0), c, size, a);
    if against_wall(rng, d, region, size, (0.0, 0.01), &build).is_none() {
        let short = (mm(uniform(rng, 1.2, 1.8)), 0.6);
        let build =
            |c: Pt, a: f32| Item::solid(format!("kitchen counter {:.2} x 0.60 m", short.0), c, short, a);
        against_wall(rng, d, region, short, (0.0, 0.01), &build);
    }
}

/// What a room is used for, which decides its furniture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Use {
    Living,
    Bedroom,
    Kitchen,
    Small,
    Hall,
    Studio,
}

pub(super) fn furnish(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], room_use: Use) {
    let area = polygon_area(region).abs();
    match room_use {
        Use::Living => {
            if chance(rng, 0.2) {
                across_corner(rng, d, region, 0.5);
            }
            sofa(rng, d, region);
            for _ in 0..rng.random_range(1..=2) {
                storage(rng, d, region, false);
            }
            if area >= 9.0 && chance(rng, 0.75) {
                let n = rng.random_range(2..=6);
                dining(rng, d, region, n);
            }
            for _ in 0..rng.random_range(1..=2) {
                small_round(rng, d, region);
            }
        }
        Use::Bedroom => {
            if chance(rng, 0.15) {
                across_corner(rng, d, region, 0.0);
            }
            bed(rng, d, region);
            storage(rng, d, region, true);
            if chance(rng, 0.5) {
                desk_with_chair(rng, d, region);
            }
            if chance(rng, 0.5) {
                small_round(rng, d, region);
            }
        }
        Use::Kitchen => {
            for _ in 0..rng.random_range(1..=2) {
                counter(rng, d, region);
            }
            if area >= 10.0 && chance(rng, 0.25) {
                let size = (mm(uniform(rng, 1.2, 2.4)), mm(uniform(rng, 0.9, 1.2)));
                let build = |c: Pt, a: f32| {
                    Item::solid(format!("kitchen island {:.2} x {:.2} m", size.0, size.1), c, size, a)
                };
                free_standing(rng, d, region, &squarish, &build);
            }
            if area >= 6.0 {
                let n = rng.random_range(2..=4);
                dining(rng, d, region, n);
            }
            small_round(rng, d, region);
        }
        Use::Small => {
            if chance(rng, 0.6) {
                storage(rng, d, region, false);
            }
            if chance(rng, 0.6) {
                small_round(rng, d, region);
            }
        }
        Use::Hall => {
            if chance(rng, 0.3) {
                let size = (mm(uniform(rng, 0.6, 1.2)), mm(uniform(rng, 0.35, 0.4)));
                let build = |c: Pt, a: f32| {
                    Item::solid(format!("hall cabinet {:.2} x {:.2} m", size.0, size.1), c, size, a)
                };
                against_wall(rng, d, region, size, (0.0, 0.02), &build);
            }
        }
        Use::Studio => {
            bed(rng, d, region);
            storage(rng, d, region, true);
            counter(rng, d, region);
            if area >= 12.0 {
                sofa(rng, d, region);
            }
            let n = rng.random_range(1..=3);
            dining(rng, d, region, n);
            if chance(rng, 0.5) {
                small_round(rng, d, region);
            }
        }
    }
}

/// Furnishes a room by its area, as in a flat.
pub(super) fn furnish_by_area(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], rank: usize, rooms: usize) {
    let area = polygon_area(region).abs();
    let room_use = if rooms == 1 {
        if area < 5.0 { Use::Small } else { Use::Studio }
    } else if area < 5.0 {
        Use::Small
    } else {
        [Use::Living, Use::Bedroom, Use::Kitchen, Use::Bedroom][rank.min(3)]
    };
    furnish(rng, d, region, room_use);
}
