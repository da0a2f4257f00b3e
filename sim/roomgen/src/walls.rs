//! Walls, doors and pockets: interior walls with door gaps, closets and units across corners.

use super::*;
use super::{draft::*, geometry::*};

/// Door openings along a wall: (start, width) pairs, sorted, within `from..to`.
pub(super) fn draw_doors(rng: &mut ChaCha8Rng, from: f32, to: f32, count: usize) -> Vec<(f32, f32)> {
    let mut doors: Vec<(f32, f32)> = Vec::new();
    for _ in 0..count {
        for _ in 0..10 {
            let width = if to - from > 3.0 && chance(rng, 0.1) {
                uniform(rng, 1.2, 1.6)
            } else {
                uniform(rng, 0.70, 0.90)
            };
            let width = mm(width);
            let start = mm(uniform(rng, from + 0.05, to - width - 0.05));
            if start < from + 0.05 || start + width > to - 0.05 {
                continue;
            }
            if doors.iter().all(|&(s, w)| start + width + 0.5 < s || s + w + 0.5 < start) {
                doors.push((start, width));
                break;
            }
        }
    }
    doors.sort_by(|a, b| a.0.total_cmp(&b.0));
    doors
}

/// A straight wall of thickness `t` on the line `x = at` (`vertical`) or `y = at`, from `span.0`
/// to `span.1`, with `doors` left open. Returns the wall item and one clearance zone per door.
pub(super) fn wall_item(
    vertical: bool,
    at: f32,
    t: f32,
    span: (f32, f32),
    doors: &[(f32, f32)],
) -> (Item, Vec<Item>) {
    let piece = |a: f32, b: f32| {
        let mid = (a + b) * 0.5;
        if vertical { rect((at, mid), (t, b - a), 0.0) } else { rect((mid, at), (b - a, t), 0.0) }
    };
    let mut parts = Vec::new();
    let mut zones = Vec::new();
    let mut cursor = span.0;
    for &(start, width) in doors {
        if start - cursor > 0.005 {
            parts.push(piece(cursor, start));
        }
        let mid = start + width * 0.5;
        let depth = t + 2.0 * DOOR_CLEARANCE;
        zones.push(Item::clear(if vertical {
            rect((at, mid), (depth, width), 0.0)
        } else {
            rect((mid, at), (width, depth), 0.0)
        }));
        cursor = start + width;
    }
    if span.1 - cursor > 0.005 {
        parts.push(piece(cursor, span.1));
    }
    let doors_text = match doors.len() {
        0 => "no door".to_string(),
        _ => doors.iter().map(|d| format!("{:.2} m", d.1)).collect::<Vec<_>>().join(" and ") + " door",
    };
    let label =
        format!("interior wall {:.0} mm thick, {} m long, {doors_text}", t * 1000.0, mm(span.1 - span.0));
    let item = Item { label, kind: Kind::Wall, footprint: piece(span.0, span.1), parts, seals: false };
    (item, zones)
}

/// Places a wall and its door zones; false (nothing placed) when it would cut a doorway.
pub(super) fn place_wall(d: &mut Draft, wall: Item, zones: Vec<Item>) -> bool {
    let n = d.placed.len();
    let doors = zones.len();
    if !d.place(wall, None) {
        return false;
    }
    for z in zones {
        if !d.place(z, None) {
            d.placed.truncate(n);
            return false;
        }
    }
    d.facts.doors += doors;
    true
}

/// A convex right-angled corner of a polygon: its point, the unit directions along its two
/// walls (away from the corner, `e2` = `e1` turned left) and the walls' lengths.
#[derive(Debug, Clone, Copy)]
pub(super) struct Corner {
    pub(super) at: Pt,
    pub(super) e1: Pt,
    pub(super) len1: f32,
    pub(super) len2: f32,
}

pub(super) fn right_corners(poly: &[Pt]) -> Vec<Corner> {
    let n = poly.len();
    (0..n)
        .filter_map(|i| {
            let (p, v, q) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            let (din, dout) = (unit(sub(v, p)), unit(sub(q, v)));
            let cross = din.0 * dout.1 - din.1 * dout.0;
            let dot = din.0 * dout.0 + din.1 * dout.1;
            (cross > 0.0 && dot.abs() < 0.02).then(|| Corner {
                at: v,
                e1: dout,
                len1: length(sub(q, v)),
                len2: length(sub(v, p)),
            })
        })
        .collect()
}

/// A closet in a corner with its door shut: two walls, no gap, floor inside kept empty.
pub(super) fn closet(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) -> bool {
    let Some(c) = pick(rng, &right_corners(region)) else { return false };
    let t = mm(uniform(rng, 0.07, 0.12));
    let a = mm(uniform(rng, 0.6, 1.2).min(c.len1 - 1.0));
    let b = mm(uniform(rng, 0.8, 2.0).min(c.len2 - 1.0));
    if a < 0.5 || b < 0.5 {
        return false;
    }
    let angle = tenth(dir_deg(c.e1));
    let at = |l: Pt| local(c.at, angle, l);
    let probe = Item {
        label: String::new(),
        kind: Kind::Solid,
        footprint: rect(at(((a + t) * 0.5, (b + t) * 0.5)), (a + t, b + t), angle),
        parts: Vec::new(),
        seals: true,
    };
    let Some(fp) = shaped(&probe.footprint) else { return false };
    if !d.fits(&probe, &fp, &[], Some(region)) {
        return false;
    }
    let walls = vec![
        rect(at((a + t * 0.5, (b + t - SEAL) * 0.5)), (t, b + t + SEAL), angle),
        rect(at(((a + t * 0.5 - SEAL) * 0.5, b + t * 0.5)), (a + t * 0.5 + SEAL, t), angle),
    ];
    let label =
        format!("closet {a:.2} x {b:.2} m inside, door shut: walls {:.0} mm, a closed pocket", t * 1000.0);
    let wall =
        Item { label, kind: Kind::Wall, footprint: probe.footprint.clone(), parts: walls, seals: true };
    let inside = Item::clear(rect(at((a * 0.5, b * 0.5)), (a, b), angle));
    if !d.place(wall, None) {
        return false;
    }
    d.place(inside, None);
    d.facts.pockets += 1;
    true
}

/// A wardrobe, shelf or sofa standing across a right-angled corner, touching both walls: the
/// triangle behind it is a closed pocket. A sofa with probability `sofa_odds`.
pub(super) fn across_corner(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], sofa_odds: f64) -> bool {
    let sofa = chance(rng, sofa_odds);
    let Some(c) = pick(rng, &right_corners(region)) else { return false };
    let (name, width, depth) = if sofa {
        ("sofa", uniform(rng, 1.6, 2.4), uniform(rng, 0.8, 1.0))
    } else {
        ("wardrobe", uniform(rng, 0.8, 2.4), uniform(rng, 0.55, 0.65))
    };
    let phi = uniform(rng, 35.0, 55.0).to_radians();
    let (p, q) = (width * phi.cos(), width * phi.sin());
    if p > c.len1 - 0.3 || q > c.len2 - 0.3 {
        return false;
    }
    let base = dir_deg(c.e1);
    let p1 = local(c.at, base, (p, 0.0));
    let p2 = local(c.at, base, (0.0, q));
    let along = unit(sub(p2, p1));
    let out = scale(left(along), -1.0);
    let center = add(scale(add(p1, p2), 0.5), scale(out, depth * 0.5));
    let mut item = Item::solid(
        format!("{name} {width:.2} x {depth:.2} m across a corner, a closed pocket behind it"),
        center,
        (width + 2.0 * SEAL, depth),
        dir_deg(along),
    );
    item.seals = true;
    if d.place(item, Some(region)) {
        d.facts.pockets += 1;
        return true;
    }
    false
}
