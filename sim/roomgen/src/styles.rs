//! The five styles: flat, office, warehouse, pillars and irregular outlines.

use super::*;
use super::{draft::*, furniture::*, geometry::*, walls::*};

/// An axis-aligned part of a flat: `outer` runs to the walls' centre lines (or the outline),
/// `inner` to their faces.
#[derive(Debug, Clone, Copy)]
pub(super) struct Part {
    pub(super) outer: [f32; 4],
    pub(super) inner: [f32; 4],
    pub(super) hall: bool,
}

impl Part {
    pub(super) fn inner_poly(&self) -> Vec<Pt> {
        let [x0, y0, x1, y1] = self.inner;
        rect_outline(x0, y0, x1, y1)
    }
}

pub(super) fn flat(rng: &mut ChaCha8Rng) -> Draft {
    let (w, h) = (mm(uniform(rng, 2.0, 10.0)), mm(uniform(rng, 2.0, 8.5)));
    let mut d = Draft::new(rect_outline(0.0, 0.0, w, h), "flat");
    let mut parts = Vec::new();
    let whole = [0.0, 0.0, w, h];
    split(rng, &mut d, Part { outer: whole, inner: whole, hall: false }, 0, &mut parts);
    d.facts.rooms = parts.len();
    if chance(rng, 0.3) {
        let rooms: Vec<usize> = (0..parts.len()).filter(|&i| !parts[i].hall).collect();
        if let Some(i) = pick(rng, &rooms) {
            closet(rng, &mut d, &parts[i].inner_poly());
        }
    }
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by(|&a, &b| {
        let area = |p: &Part| (p.inner[2] - p.inner[0]) * (p.inner[3] - p.inner[1]);
        area(&parts[b]).total_cmp(&area(&parts[a])).then(a.cmp(&b))
    });
    let rooms = parts.iter().filter(|p| !p.hall).count();
    let mut rank = 0;
    for i in order {
        let region = parts[i].inner_poly();
        if parts[i].hall {
            furnish(rng, &mut d, &region, Use::Hall);
        } else {
            furnish_by_area(rng, &mut d, &region, rank, rooms);
            rank += 1;
        }
    }
    d
}

/// Splits a part of a flat with an interior wall (with doors) and recurses, or keeps it as a room.
pub(super) fn split(rng: &mut ChaCha8Rng, d: &mut Draft, part: Part, depth: u8, out: &mut Vec<Part>) {
    let [ix0, iy0, ix1, iy1] = part.inner;
    let (iw, ih) = (ix1 - ix0, iy1 - iy0);
    let long = iw.max(ih);
    let p = if depth == 0 { 0.85 } else { 0.5 };
    if part.hall || depth >= 2 || long < 4.2 || !chance(rng, p) {
        out.push(part);
        return;
    }
    let t = mm(uniform(rng, 0.07, 0.15));
    let hall = depth == 0 && iw.min(ih) >= 4.0 && chance(rng, 0.3);
    for _ in 0..8 {
        // A wall across the long side (rooms side by side), or along it to cut off a hall.
        let vertical = (iw >= ih) != hall;
        let (lo, hi) = if vertical { (ix0, ix1) } else { (iy0, iy1) };
        let at = if hall {
            let width = uniform(rng, 0.9, 1.2) + t * 0.5;
            if chance(rng, 0.5) { lo + width } else { hi - width }
        } else {
            uniform(rng, lo + 2.0 + t * 0.5, hi - 2.0 - t * 0.5)
        };
        let at = mm(at);
        let [ox0, oy0, ox1, oy1] = part.outer;
        let (span, inner_span) = if vertical { ((oy0, oy1), (iy0, iy1)) } else { ((ox0, ox1), (ix0, ix1)) };
        let inner_len = inner_span.1 - inner_span.0;
        let count = if hall {
            1 + (inner_len / 3.5) as usize
        } else {
            1 + usize::from(inner_len > 4.5 && chance(rng, 0.5))
        };
        let doors = draw_doors(rng, inner_span.0, inner_span.1, count);
        if doors.is_empty() {
            continue;
        }
        let (wall, zones) = wall_item(vertical, at, t, span, &doors);
        if !place_wall(d, wall, zones) {
            continue;
        }
        let (mut a, mut b) = (part, part);
        a.hall = false;
        b.hall = false;
        let (k_outer, k_inner) = if vertical { (2, 0) } else { (3, 1) };
        a.outer[k_outer] = at;
        a.inner[k_outer] = at - t * 0.5;
        b.outer[k_inner] = at;
        b.inner[k_inner] = at + t * 0.5;
        if hall {
            let a_is_hall = (a.inner[k_outer] - a.inner[k_inner]) < (b.inner[k_outer] - b.inner[k_inner]);
            a.hall = a_is_hall;
            b.hall = !a_is_hall;
        }
        split(rng, d, a, depth + 1, out);
        split(rng, d, b, depth + 1, out);
        return;
    }
    out.push(part);
}

pub(super) fn office(rng: &mut ChaCha8Rng) -> Draft {
    let (w, h) = (mm(uniform(rng, 4.5, 12.5)), mm(uniform(rng, 4.0, 10.5)));
    let mut d = Draft::new(rect_outline(0.0, 0.0, w, h), "office");
    let mut open_top = h;
    // Cellular offices and meeting rooms behind a partition along the top.
    if w >= 6.0 && h >= 6.5 && chance(rng, 0.6) {
        let t = mm(uniform(rng, 0.07, 0.15));
        let at = mm(h - uniform(rng, 2.4, 3.5));
        let n = ((w / uniform(rng, 2.4, 4.0)) as usize).clamp(1, 4);
        let mut xs = vec![0.0];
        for k in 1..n {
            xs.push(mm(k as f32 * w / n as f32 + uniform(rng, -0.3, 0.3)));
        }
        xs.push(w);
        let store = if n >= 2 && chance(rng, 0.15) { Some(rng.random_range(0..n)) } else { None };
        let mut doors = Vec::new();
        for k in 0..n {
            let (a, b) = (
                xs[k] + if k > 0 { t * 0.5 } else { 0.0 },
                xs[k + 1] - if k + 1 < n { t * 0.5 } else { 0.0 },
            );
            if store != Some(k) {
                doors.extend(draw_doors(rng, a, b, 1));
            }
        }
        let (wall, zones) = wall_item(false, at, t, (0.0, w), &doors);
        if place_wall(&mut d, wall, zones) {
            open_top = at - t * 0.5;
            for &x in &xs[1..n] {
                let (wall, zones) = wall_item(true, x, t, (at, h), &[]);
                place_wall(&mut d, wall, zones);
            }
            for k in 0..n {
                let x0 = xs[k] + if k > 0 { t * 0.5 } else { 0.0 };
                let x1 = xs[k + 1] - if k + 1 < n { t * 0.5 } else { 0.0 };
                let region = rect_outline(x0, at + t * 0.5, x1, h);
                if store == Some(k) {
                    d.facts.pockets += 1;
                    for _ in 0..2 {
                        storage(rng, &mut d, &region, false);
                    }
                } else if chance(rng, 0.5) {
                    let n = rng.random_range(3..=6);
                    dining(rng, &mut d, &region, n);
                } else {
                    desk_with_chair(rng, &mut d, &region);
                    storage(rng, &mut d, &region, false);
                }
            }
            d.facts.rooms = n;
        }
    }
    d.facts.rooms += 1;
    // A corridor kept clear along the top of the open area.
    let corridor = mm(uniform(rng, 1.2, 2.0));
    d.place(Item::clear(rect((w * 0.5, open_top - corridor * 0.5), (w, corridor), 0.0)), None);
    let region = rect_outline(0.0, 0.0, w, open_top);
    // One desk model for the whole office.
    let desk = (mm(uniform(rng, 1.0, 1.6)), mm(uniform(rng, 0.6, 0.8)));
    let legs = Legs::draw(rng, 0.03, 0.06, 0.45);
    let aisle = uniform(rng, 1.6, 2.6);
    let mut y = if chance(rng, 0.3) { uniform(rng, 0.02, 0.06) } else { uniform(rng, 1.0, 1.6) };
    let mut first = true;
    loop {
        let double = !(first && y < 0.1) && chance(rng, 0.6);
        let depth = if double { 2.0 * desk.1 } else { desk.1 };
        // Room for the chairs between the last row and the corridor.
        if y + depth + 0.7 > open_top - corridor {
            break;
        }
        desk_row(rng, &mut d, &region, desk, legs, y, double, w, first && y < 0.1);
        y += depth + aisle + uniform(rng, -0.05, 0.05);
        first = false;
    }
    for _ in 0..rng.random_range(2..=4) {
        storage(rng, &mut d, &region, false);
    }
    for _ in 0..rng.random_range(1..=3) {
        small_round(rng, &mut d, &region);
    }
    d
}

/// One row of desk banks along x starting at height `y`: single (chairs above) or back to back.
#[allow(clippy::too_many_arguments)]
pub(super) fn desk_row(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    desk: Pt,
    legs: Legs,
    y: f32,
    double: bool,
    w: f32,
    against: bool,
) {
    let mut x = uniform(rng, 0.9, 1.8);
    while x + 2.0 * desk.0 < w - 0.9 {
        let n = rng.random_range(2..=4usize);
        for _ in 0..n {
            let cx = x + desk.0 * 0.5;
            if cx + desk.0 * 0.5 > w - 0.9 {
                break;
            }
            for row in 0..(1 + usize::from(double)) {
                let cy = y + desk.1 * (0.5 + row as f32) + if row == 1 { 0.02 } else { 0.0 };
                let label = format!("desk {:.2} x {:.2} m in a bank, {}", desk.0, desk.1, legs.describe());
                let item = Item::legged(label, Kind::Legged, (cx, cy), desk, 0.0, legs);
                if d.place(item, Some(region)) {
                    // Chairs on the open side: below the first row of a pair, above otherwise.
                    let side = if double && row == 0 { 0 } else { 1 };
                    if !(against && side == 0) && chance(rng, 0.9) {
                        let along = uniform(rng, -0.25, 0.25);
                        chair_at(rng, d, region, (mm(cx), mm(cy)), desk, 0.0, side, along);
                    }
                }
            }
            x += desk.0 + uniform(rng, 0.005, 0.03);
        }
        x += uniform(rng, 1.2, 2.0);
    }
}

pub(super) fn warehouse(rng: &mut ChaCha8Rng) -> Draft {
    // Drawn with racks along x, then transposed half the time.
    let (l, w) = (mm(uniform(rng, 8.0, 14.5)), mm(uniform(rng, 6.0, 12.5)));
    let transpose = chance(rng, 0.5);
    let room = if transpose { rect_outline(0.0, 0.0, w, l) } else { rect_outline(0.0, 0.0, l, w) };
    let mut d = Draft::new(room, "warehouse");
    d.facts.rooms = 1;
    let flip = |p: Pt| if transpose { (p.1, p.0) } else { p };
    let region = d.room.clone();
    let depth = mm(uniform(rng, 0.4, 1.2));
    let aisle = uniform(rng, 1.0, 3.0);
    let cross = uniform(rng, 1.5, 3.0);
    let two_runs = l >= 2.0 * 5.0 + cross + 2.0 && chance(rng, 0.5);
    let (run, cross) = if two_runs {
        (uniform(rng, 5.0, ((l - cross - 2.0) * 0.5).min(10.0)), cross)
    } else {
        (uniform(rng, 5.0, 10.0).min(l - 2.0), 0.0)
    };
    let x_start = uniform(rng, 1.0, (l - run * if two_runs { 2.0 } else { 1.0 } - cross - 1.0).max(1.0));
    // Rows across the room: often a single rack against the first wall, then double or single
    // racks between aisles, and a single rack against the far wall when one fits there.
    let rack_row = |d: &mut Draft, y: f32, depth: f32, double: bool| {
        for k in 0..(1 + usize::from(two_runs)) {
            let x0 = x_start + k as f32 * (run + cross);
            let size = (mm(run), mm(depth));
            let center = flip((x0 + run * 0.5, y + depth * 0.5));
            let size = if transpose { (size.1, size.0) } else { size };
            let kind = if double { "back-to-back racks" } else { "rack" };
            let label = format!("{kind} {:.2} m long, {:.2} m deep", mm(run), mm(depth));
            if d.place(Item::solid(label, center, size, 0.0), Some(region.as_slice())) {
                d.facts.racks += 1;
            }
        }
    };
    let against_first = chance(rng, 0.6);
    let mut y = if against_first { uniform(rng, 0.02, 0.1) } else { aisle + uniform(rng, -0.05, 0.05) };
    let mut first = true;
    loop {
        let double = !(first && against_first) && chance(rng, 0.7);
        let rack_depth = if double { 2.0 * depth + uniform(rng, 0.0, 0.2) } else { depth };
        if y + rack_depth > w - 0.9 {
            break;
        }
        rack_row(&mut d, y, rack_depth, double);
        y += rack_depth + aisle + uniform(rng, -0.05, 0.05);
        first = false;
    }
    // y is now where the next rack would start, one aisle past the last one.
    let far = w - depth - uniform(rng, 0.02, 0.1);
    if far >= y - aisle + 1.0 && chance(rng, 0.6) {
        rack_row(&mut d, far, depth, false);
    }
    for _ in 0..rng.random_range(1..=4) {
        let size = (1.2, 0.8);
        let build = |c: Pt, a: f32| Item::solid("pallet 1.20 x 0.80 m".to_string(), c, size, a);
        free_standing(rng, &mut d, &region, &home_angle, &build);
    }
    for _ in 0..rng.random_range(0..=2) {
        small_round(rng, &mut d, &region);
    }
    d
}

pub(super) fn pillars(rng: &mut ChaCha8Rng) -> Draft {
    let (w, h) = (mm(uniform(rng, 6.0, 14.0)), mm(uniform(rng, 6.0, 12.0)));
    let mut d = Draft::new(rect_outline(0.0, 0.0, w, h), "hall with pillars");
    d.facts.rooms = 1;
    let region = d.room.clone();
    let round = chance(rng, 0.5);
    let size = if round { mm(uniform(rng, 0.2, 0.5)) } else { mm(uniform(rng, 0.3, 0.6)) };
    let (sx, sy) = (uniform(rng, 5.0, 8.0), uniform(rng, 5.0, 8.0));
    let (ox, oy) = (uniform(rng, 0.8, sx.min(w - 0.8)), uniform(rng, 0.8, sy.min(h - 0.8)));
    let line = |o: f32, s: f32, max: f32| (0..).map(move |k| o + k as f32 * s).take_while(move |&v| v <= max);
    let xs: Vec<f32> = line(ox, sx, w - 0.8).collect();
    let ys: Vec<f32> = line(oy, sy, h - 0.8).collect();
    // Half-pillars engaged in the outer walls, where the structural grid meets them.
    if !round && chance(rng, 0.4) {
        let p = mm(uniform(rng, 0.1, 0.3));
        let mut engaged = Vec::new();
        for &x in &xs {
            engaged.push(((x, p * 0.5 - SEAL), (size, p + 2.0 * SEAL)));
            engaged.push(((x, h - p * 0.5 + SEAL), (size, p + 2.0 * SEAL)));
        }
        for &y in &ys {
            engaged.push(((p * 0.5 - SEAL, y), (p + 2.0 * SEAL, size)));
            engaged.push(((w - p * 0.5 + SEAL, y), (p + 2.0 * SEAL, size)));
        }
        for (c, s) in engaged {
            let fp = rect(c, s, 0.0);
            let label = format!("half-pillar {size:.2} m wide, {p:.2} m out of the wall");
            d.place(
                Item { label, kind: Kind::Wall, parts: vec![fp.clone()], footprint: fp, seals: true },
                None,
            );
        }
    }
    for &y in &ys {
        for &x in &xs {
            let item = if round {
                Item::round(format!("round pillar {size:.2} m across"), (x, y), size * 0.5)
            } else {
                Item::solid(format!("square pillar {size:.2} m"), (x, y), (size, size), 0.0)
            };
            if d.place(item, Some(region.as_slice())) {
                d.facts.pillars += 1;
            }
        }
    }
    if chance(rng, 0.1) {
        across_corner(rng, &mut d, &region, 0.5);
    }
    for _ in 0..rng.random_range(1..=3) {
        storage(rng, &mut d, &region, false);
    }
    if chance(rng, 0.6) {
        let n = rng.random_range(2..=6);
        dining(rng, &mut d, &region, n);
    }
    if chance(rng, 0.5) {
        sofa(rng, &mut d, &region);
    }
    if chance(rng, 0.4) {
        desk_with_chair(rng, &mut d, &region);
    }
    for _ in 0..rng.random_range(0..=3) {
        small_round(rng, &mut d, &region);
    }
    d
}

/// What happens at one corner of an irregular room's rectangle.
#[derive(Debug, Clone, Copy)]
pub(super) enum CornerCut {
    /// Left square.
    None,
    /// Cut by a straight wall `a` back along the incoming side and `b` along the outgoing one
    /// (a = b: 45°).
    Chamfer(f32, f32),
    /// Moved `by` along the outgoing side: the incoming wall becomes slanted.
    Slant(f32),
    /// An L: a `p` × `q` rectangle cut out.
    Notch(f32, f32),
}

pub(super) fn irregular_outline(rng: &mut ChaCha8Rng) -> Vec<Pt> {
    for _ in 0..32 {
        let (w, h) = (uniform(rng, 2.0, 7.5), uniform(rng, 2.0, 7.0));
        let corner_pts = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)];
        // Side i runs from corner i to corner i + 1; its length is w for even i, h for odd i.
        let side_len = |i: usize| if i.is_multiple_of(2) { w } else { h };
        let mut cuts = [CornerCut::None; 4];
        let count = rng.random_range(1..=3usize);
        let mut notched = false;
        for _ in 0..count {
            let i = rng.random_range(0..4usize);
            let (incoming, outgoing) = (side_len((i + 3) % 4), side_len(i));
            let short = incoming.min(outgoing);
            cuts[i] = match rng.random_range(0..4u8) {
                0 => {
                    let a = uniform(rng, 0.3, (0.35 * short).min(1.5));
                    CornerCut::Chamfer(a, a)
                }
                1 => {
                    let a = uniform(rng, 0.3, (0.35 * short).min(1.5));
                    let b = a * uniform(rng, 30.0, 60.0).to_radians().tan();
                    CornerCut::Chamfer(a, b.min(0.4 * outgoing))
                }
                2 => CornerCut::Slant(uniform(rng, 0.3, (0.3 * outgoing).min(1.5))),
                _ if !notched && w >= 3.0 && h >= 3.0 => {
                    notched = true;
                    CornerCut::Notch(uniform(rng, 0.9, incoming - 0.9), uniform(rng, 0.9, outgoing - 0.9))
                }
                _ => CornerCut::Chamfer(0.3, 0.3),
            };
        }
        let bay_side = if chance(rng, 0.35) { Some(rng.random_range(0..4usize)) } else { None };
        let mut poly = Vec::new();
        for i in 0..4 {
            let v = corner_pts[i];
            let din = unit(sub(v, corner_pts[(i + 3) % 4]));
            let dout = unit(sub(corner_pts[(i + 1) % 4], v));
            match cuts[i] {
                CornerCut::None => poly.push(v),
                CornerCut::Chamfer(a, b) => {
                    poly.push(sub(v, scale(din, a)));
                    poly.push(add(v, scale(dout, b)));
                }
                CornerCut::Slant(by) => poly.push(add(v, scale(dout, by))),
                CornerCut::Notch(p, q) => {
                    let inner = sub(v, scale(din, p));
                    poly.push(inner);
                    poly.push(add(inner, scale(dout, q)));
                    poly.push(add(v, scale(dout, q)));
                }
            }
            // A bay window with 45° sides on side i, between plain or chamfered corners.
            let plain = |c: CornerCut| matches!(c, CornerCut::None | CornerCut::Chamfer(..));
            if bay_side == Some(i) && plain(cuts[i]) && plain(cuts[(i + 1) % 4]) {
                let len = side_len(i);
                let used = |c: CornerCut, first: bool| match c {
                    CornerCut::Chamfer(a, b) => {
                        if first {
                            b
                        } else {
                            a
                        }
                    }
                    _ => 0.0,
                };
                let (from, to) = (used(cuts[i], true) + 0.2, len - used(cuts[(i + 1) % 4], false) - 0.2);
                let bw = uniform(rng, 1.2, 2.4);
                let bd = uniform(rng, 0.4, 0.9);
                if to - from > bw && bw > 2.0 * bd + 0.3 {
                    let s = uniform(rng, from, to - bw);
                    let out = scale(left(dout), -1.0);
                    let p0 = add(v, scale(dout, s));
                    poly.push(p0);
                    poly.push(add(add(p0, scale(dout, bd)), scale(out, bd)));
                    poly.push(add(add(p0, scale(dout, bw - bd)), scale(out, bd)));
                    poly.push(add(p0, scale(dout, bw)));
                }
            }
        }
        let aabb = grid::room_aabb(&poly);
        let (x0, y0) = (aabb.mins.x, aabb.mins.y);
        let poly: Vec<Pt> = poly.iter().map(|&(x, y)| (mm(x - x0), mm(y - y0))).collect();
        if is_simple(&poly) {
            return poly;
        }
    }
    rect_outline(0.0, 0.0, 3.0, 3.0)
}

/// Whether a polygon is simple and counter-clockwise: no edge shorter than 5 cm, no edge folding
/// back, no two non-adjacent edges meeting.
pub(super) fn is_simple(poly: &[Pt]) -> bool {
    let n = poly.len();
    let edge = |i: usize| (poly[i], poly[(i + 1) % n]);
    if (0..n).any(|i| length(sub(edge(i).1, edge(i).0)) < 0.05) || polygon_area(poly) <= 0.0 {
        return false;
    }
    // No wall folds back on the one before it.
    let folds = (0..n).any(|i| {
        let (a, b) = (unit(sub(edge(i).1, edge(i).0)), unit(sub(edge((i + 1) % n).1, edge((i + 1) % n).0)));
        a.0 * b.0 + a.1 * b.1 < -0.99
    });
    if folds {
        return false;
    }
    let cross = |o: Pt, a: Pt, b: Pt| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    for i in 0..n {
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let ((a, b), (c, e)) = (edge(i), edge(j));
            let (d1, d2) = (cross(c, e, a), cross(c, e, b));
            let (d3, d4) = (cross(a, b, c), cross(a, b, e));
            if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 {
                return false;
            }
        }
    }
    true
}

pub(super) fn irregular(rng: &mut ChaCha8Rng) -> Draft {
    let outline = irregular_outline(rng);
    let mut d = Draft::new(outline, "irregular room");
    d.facts.rooms = 1;
    let region = d.room.clone();
    if chance(rng, 0.2) {
        closet(rng, &mut d, &region);
    } else if chance(rng, 0.2) {
        across_corner(rng, &mut d, &region, 0.4);
    }
    let area = polygon_area(&region).abs();
    let room_use = if area < 5.0 {
        Use::Small
    } else if area < 12.0 {
        pick(rng, &[Use::Bedroom, Use::Kitchen]).unwrap_or(Use::Bedroom)
    } else {
        pick(rng, &[Use::Living, Use::Studio]).unwrap_or(Use::Living)
    };
    furnish(rng, &mut d, &region, room_use);
    d
}
