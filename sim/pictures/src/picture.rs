//! Drawing on the pictures `explobot` writes (`map.png`, `truth.png`): lines, tints, text and a
//! legend strip under the picture.
//!
//! Text uses the public-domain 8 × 8 ASCII glyphs of the `font8x8` crate, so the pictures need no
//! font file and stay byte-identical from run to run. Characters outside ASCII draw as nothing.
//!
//! ```
//! use image::RgbImage;
//! use twin_pictures::picture::{LegendEntry, Swatch, with_legend};
//! let img = RgbImage::new(200, 100);
//! let entries = [LegendEntry::new(Swatch::Fill([255, 255, 255]), "floor")];
//! let out = with_legend(img, &entries);
//! assert_eq!(out.width(), 200);
//! assert!(out.height() > 100); // the legend strip is added below
//! ```

use font8x8::legacy::BASIC_LEGACY;
use image::{Rgb, RgbImage};

/// Glyph side, pixels (one glyph pixel per image pixel).
const GLYPH: u32 = 8;
/// Height of one legend row, pixels.
const ROW: u32 = 18;
/// Swatch width, pixels.
const SWATCH: u32 = 22;
/// Space between legend entries and around the strip, pixels.
const PAD: u32 = 10;
/// Legend background and text colours.
const BACKGROUND: [u8; 3] = [245, 245, 245];
const INK: [u8; 3] = [20, 20, 20];

/// `base` mixed with `tint`, `alpha` of the way.
pub fn blend(base: [u8; 3], tint: [u8; 3], alpha: f32) -> [u8; 3] {
    let mix = |a: u8, b: u8| (a as f32 * (1.0 - alpha) + b as f32 * alpha).round() as u8;
    [mix(base[0], tint[0]), mix(base[1], tint[1]), mix(base[2], tint[2])]
}

/// Draws a 2-pixel line between two pixel positions, clipped to the image.
pub fn line(img: &mut RgbImage, from: (f32, f32), to: (f32, f32), color: [u8; 3]) {
    let (dx, dy) = (to.0 - from.0, to.1 - from.1);
    let n = dx.abs().max(dy.abs()).ceil().max(1.0) as u32;
    for i in 0..=n {
        let t = i as f32 / n as f32;
        let (x, y) = (from.0 + dx * t, from.1 + dy * t);
        for (ox, oy) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5)] {
            put(img, (x + ox).floor(), (y + oy).floor(), color);
        }
    }
}

/// Draws a dashed polyline through pixel positions: `dash` pixels drawn, `dash` left out, counted
/// along the whole path so that short segments still show the dashes.
pub fn dashed_polyline(img: &mut RgbImage, points: &[(f32, f32)], color: [u8; 3], dash: f32) {
    let dash = dash.max(1.0);
    let mut travelled = 0.0f32;
    for pair in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (pair[0], pair[1]);
        let (dx, dy) = (x1 - x0, y1 - y0);
        let length = dx.hypot(dy);
        let n = length.ceil().max(1.0) as u32;
        for i in 0..n {
            let t = i as f32 / n as f32;
            if (((travelled + length * t) / dash) as u64).is_multiple_of(2) {
                let (x, y) = (x0 + dx * t, y0 + dy * t);
                for (ox, oy) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5)] {
                    put(img, (x + ox).floor(), (y + oy).floor(), color);
                }
            }
        }
        travelled += length;
    }
}

/// Fills the pixel rectangle `[x0, x1) × [y0, y1)`, clipped to the image.
pub fn fill(img: &mut RgbImage, (x0, y0): (u32, u32), (x1, y1): (u32, u32), color: [u8; 3]) {
    for y in y0..y1.min(img.height()) {
        for x in x0..x1.min(img.width()) {
            img.put_pixel(x, y, Rgb(color));
        }
    }
}

/// Writes `text` with its top-left corner at pixel `(x, y)`; returns the x after the last glyph.
pub fn text(img: &mut RgbImage, (x, y): (u32, u32), text: &str, color: [u8; 3]) -> u32 {
    let mut left = x;
    for ch in text.chars() {
        if let Some(rows) = BASIC_LEGACY.get(ch as usize) {
            for (dy, bits) in rows.iter().enumerate() {
                for dx in 0..GLYPH {
                    if bits & (1 << dx) != 0 {
                        put(img, (left + dx) as f32, (y + dy as u32) as f32, color);
                    }
                }
            }
        }
        left += GLYPH;
    }
    left
}

/// How an entry of the legend is shown.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Swatch {
    /// A filled square: an area colour.
    Fill([u8; 3]),
    /// A square of `base` tinted by `tint` as the picture does: a cell colour over the floor.
    Tint {
        /// The colour under the tint.
        base: [u8; 3],
        /// The tint.
        tint: [u8; 3],
        /// How much of the tint.
        alpha: f32,
    },
    /// A line: a trail.
    Line([u8; 3]),
    /// A dashed line.
    Dashed([u8; 3]),
}

/// One entry of the legend: a swatch and what it means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegendEntry {
    /// The swatch.
    pub swatch: Swatch,
    /// What it means (ASCII).
    pub label: &'static str,
}

impl LegendEntry {
    /// An entry.
    pub const fn new(swatch: Swatch, label: &'static str) -> LegendEntry {
        LegendEntry { swatch, label }
    }

    fn width(&self) -> u32 {
        SWATCH + 6 + self.label.len() as u32 * GLYPH
    }
}

/// `img` with a legend strip added below it: the entries left to right, wrapped to the width.
pub fn with_legend(img: RgbImage, entries: &[LegendEntry]) -> RgbImage {
    let width = img.width().max(1);
    // Lay the entries out in rows.
    let mut rows: Vec<Vec<&LegendEntry>> = vec![Vec::new()];
    let mut used = PAD;
    for entry in entries {
        let w = entry.width() + PAD;
        if used + w > width && rows.last().is_some_and(|r| !r.is_empty()) {
            rows.push(Vec::new());
            used = PAD;
        }
        if let Some(row) = rows.last_mut() {
            row.push(entry);
        }
        used += w;
    }
    let strip = PAD + rows.len() as u32 * ROW;
    let mut out = RgbImage::from_pixel(width, img.height() + strip, Rgb(BACKGROUND));
    for (x, y, p) in img.enumerate_pixels() {
        out.put_pixel(x, y, *p);
    }
    for (i, row) in rows.iter().enumerate() {
        let top = img.height() + PAD / 2 + i as u32 * ROW + (ROW - GLYPH) / 2;
        let mut x = PAD;
        for entry in row {
            draw_swatch(&mut out, (x, top), entry.swatch);
            text(&mut out, (x + SWATCH + 6, top), entry.label, INK);
            x += entry.width() + PAD;
        }
    }
    out
}

fn draw_swatch(img: &mut RgbImage, (x, y): (u32, u32), swatch: Swatch) {
    let mid = (y + GLYPH / 2) as f32 - 0.5;
    match swatch {
        Swatch::Fill(c) => fill(img, (x, y), (x + SWATCH, y + GLYPH), c),
        Swatch::Tint { base, tint, alpha } => {
            fill(img, (x, y), (x + SWATCH, y + GLYPH), blend(base, tint, alpha))
        }
        Swatch::Line(c) => line(img, (x as f32, mid), ((x + SWATCH) as f32, mid), c),
        Swatch::Dashed(c) => dashed_polyline(img, &[(x as f32, mid), ((x + SWATCH) as f32, mid)], c, 4.0),
    }
    if matches!(swatch, Swatch::Fill(_) | Swatch::Tint { .. }) {
        // A thin frame so that a white swatch shows on the light strip.
        let frame = [120, 120, 120];
        let (x0, y0, x1, y1) = (x as f32, y as f32, (x + SWATCH - 1) as f32, (y + GLYPH - 1) as f32);
        for (a, b) in [((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)), ((x0, y1), (x0, y0))]
        {
            thin_line(img, a, b, frame);
        }
    }
}

/// A 1-pixel line.
fn thin_line(img: &mut RgbImage, from: (f32, f32), to: (f32, f32), color: [u8; 3]) {
    let (dx, dy) = (to.0 - from.0, to.1 - from.1);
    let n = dx.abs().max(dy.abs()).ceil().max(1.0) as u32;
    for i in 0..=n {
        let t = i as f32 / n as f32;
        put(img, (from.0 + dx * t).round(), (from.1 + dy * t).round(), color);
    }
}

fn put(img: &mut RgbImage, x: f32, y: f32, color: [u8; 3]) {
    if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, Rgb(color));
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn text_draws_the_glyphs_of_the_font() {
        let mut img = RgbImage::from_pixel(40, 10, Rgb([0, 0, 0]));
        let end = text(&mut img, (1, 1), "H", [255, 255, 255]);
        assert_eq!(end, 9);
        let lit: Vec<(u32, u32)> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 == [255, 255, 255])
            .map(|(x, y, _)| (x, y))
            .collect();
        // font8x8's 'H' has both uprights: its first row is bits 0,1 and 4,5 (0x33).
        assert!(lit.contains(&(1, 1)) && lit.contains(&(2, 1)) && lit.contains(&(5, 1)));
        assert!(!lit.contains(&(3, 1)));
        assert!(lit.iter().all(|&(x, y)| (1..9).contains(&x) && (1..9).contains(&y)));
    }

    #[test]
    fn the_legend_wraps_to_the_picture_width() {
        let entries = [LegendEntry::new(Swatch::Line([0, 0, 255]), "a rather long label"); 4];
        let narrow = with_legend(RgbImage::new(200, 50), &entries);
        let wide = with_legend(RgbImage::new(1200, 50), &entries);
        assert_eq!(narrow.height(), 50 + PAD + 4 * ROW);
        assert_eq!(wide.height(), 50 + PAD + ROW);
        // The picture itself is untouched.
        assert_eq!(*wide.get_pixel(10, 10), Rgb([0, 0, 0]));
    }
}
