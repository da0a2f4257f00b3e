//! The "Carto's map" layer of the world view: Carto's own evidence grid laid over the true room
//! (free cells a faint cyan, occupied cells teal, as in `map.png`) and its belief, an orange
//! heading tick inside the 2σ ellipse of its position ([`twin::carto_map`]). The toggle button
//! of the same name in the time controls shows or hides it; it starts shown.
//!
//! Concept: the grid is a texture over the room's box at the grid's own resolution, repainted at
//! most every [`REPAINT_EVERY_S`] of wall time while the layer is shown (and at once when it is
//! turned on); the belief is drawn with gizmos every frame.

use bevy::asset::{Assets, RenderAssetUsages};
use bevy::color::Color;
use bevy::ecs::system::{Commands, Res, ResMut, Single};
use bevy::gizmos::gizmos::Gizmos;
use bevy::image::{Image, ImageSampler};
use bevy::math::Vec2;
use bevy::prelude::{Component, Resource, Transform, Visibility, With};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::sprite::Sprite;
use bevy::time::{Real, Time};
use bevy::window::{PrimaryWindow, Window};
use cute::gui::logical_to_world;

use super::layout::{WorldLayout, room_box};
use crate::plugin::Sim;
use twin::carto_map::{BeliefEllipse, CartoMap, Occupancy};

/// Repaint the grid's texture at most this often, wall seconds.
pub const REPAINT_EVERY_S: f64 = 0.25;
/// Largest texture side, texels (a grid cell may then take less than a texel).
const MAX_SIDE: f32 = 2048.0;
/// Texel colours, RGBA: Carto's free and occupied cells (the colours of `map.png`).
const FREE_RGBA: [u8; 4] = [0, 170, 210, 70];
const OCCUPIED_RGBA: [u8; 4] = [0, 120, 130, 235];
/// Carto's belief: the same orange as its trail in `map.png`.
const BELIEF: Color = Color::srgb(0.96, 0.55, 0.0);

/// Whether the layer is shown, and when its texture was last painted.
#[derive(Resource, Debug)]
pub struct CartoLayer {
    /// Shown (toggled by the "Carto's map" button).
    pub shown: bool,
    painted_at_s: Option<f64>,
}

impl Default for CartoLayer {
    fn default() -> Self {
        CartoLayer { shown: true, painted_at_s: None }
    }
}

impl CartoLayer {
    /// Shows the layer if hidden and hides it if shown; a shown layer is repainted at once.
    pub fn toggle(&mut self) {
        self.shown = !self.shown;
        self.painted_at_s = None;
    }
}

#[derive(Component)]
pub(super) struct CartoGridSprite {
    /// Texels per metre.
    texels_per_m: f32,
}

pub(super) fn spawn_layer(mut commands: Commands, sim: Res<Sim>, mut images: ResMut<Assets<Image>>) {
    let (min, max) = room_box(&sim.0.loaded().scenario.room);
    let size = max - min;
    let cell = sim.0.carto().evidence().params().resolution_m as f32;
    let texels_per_m = (1.0 / cell).min(MAX_SIDE / size.x.max(size.y).max(1e-3));
    let (w, h) =
        (((size.x * texels_per_m).ceil() as u32).max(1), ((size.y * texels_per_m).ceil() as u32).max(1));
    let mut image = Image::new(
        Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        TextureDimension::D2,
        vec![0; (w * h * 4) as usize],
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::RENDER_WORLD | RenderAssetUsages::MAIN_WORLD,
    );
    image.sampler = ImageSampler::nearest();
    let handle = images.add(image);
    commands.spawn((
        CartoGridSprite { texels_per_m },
        Sprite { image: handle, custom_size: Some(Vec2::ONE), ..Sprite::default() },
        Transform::default(),
        Visibility::Hidden,
    ));
}

/// Places the grid's sprite over the floor, repaints it when due, and draws the belief.
pub(super) fn draw_layer(
    sim: Res<Sim>,
    mut layer: ResMut<CartoLayer>,
    time: Res<Time<Real>>,
    window: Single<&Window, With<PrimaryWindow>>,
    sprite: Single<(&CartoGridSprite, &Sprite, &mut Transform, &mut Visibility)>,
    mut images: ResMut<Assets<Image>>,
    mut gizmos: Gizmos,
) {
    let (grid, sprite, mut transform, mut visibility) = sprite.into_inner();
    if !layer.shown {
        *visibility = Visibility::Hidden;
        return;
    }
    let run = &sim.0;
    let size = window.size();
    let layout = WorldLayout::compute(size, &run.loaded().scenario.room);
    let (min, max) = room_box(&run.loaded().scenario.room);
    let w = |x: f32, y: f32| logical_to_world(size, layout.to_logical(x, y));
    let centre = w((min.x + max.x) * 0.5, (min.y + max.y) * 0.5);
    // above the floor (0), under the robot's body (2) and wheels (3)
    *transform =
        Transform::from_translation(centre.extend(1.0)).with_scale(((max - min) * layout.scale).extend(1.0));
    *visibility = Visibility::Inherited;

    let wall = time.elapsed_secs_f64();
    if layer.painted_at_s.is_none_or(|t| wall - t >= REPAINT_EVERY_S) {
        layer.painted_at_s = Some(wall);
        if let Some(mut image) = images.get_mut(&sprite.image) {
            paint(&mut image, &CartoMap::of(run.carto(), &run.frame()), min, max, grid.texels_per_m);
        }
    }

    if let Some(belief) = BeliefEllipse::of(run.carto(), &run.frame(), run.now()) {
        let outline: Vec<Vec2> = belief.outline(48).into_iter().map(|(x, y)| w(x, y)).collect();
        gizmos.linestrip_2d(outline.iter().copied().chain(outline.first().copied()), BELIEF);
        let (x, y, heading) = belief.pose;
        let reach = run.loaded().profile.geometry.body_length_m * 0.4;
        gizmos.line_2d(w(x, y), w(x + reach * heading.cos(), y + reach * heading.sin()), BELIEF);
    }
}

/// Paints Carto's cells into the texture covering the world box `min`–`max` (row 0 at the top).
fn paint(image: &mut Image, map: &CartoMap, min: Vec2, max: Vec2, texels_per_m: f32) {
    let (width, height) = (image.texture_descriptor.size.width, image.texture_descriptor.size.height);
    let Some(data) = image.data.as_mut() else {
        return;
    };
    data.fill(0);
    let half = map.cell_m * 0.5;
    for &((x, y), occupancy) in &map.cells {
        let rgba = match occupancy {
            Occupancy::Free => FREE_RGBA,
            Occupancy::Occupied => OCCUPIED_RGBA,
            Occupancy::Unknown => continue,
        };
        let col = |x: f32| ((x - min.x) * texels_per_m).round().clamp(0.0, width as f32) as u32;
        let row = |y: f32| ((max.y - y) * texels_per_m).round().clamp(0.0, height as f32) as u32;
        let (c0, c1) = (col(x - half), col(x + half).max(col(x - half) + 1).min(width));
        let (r0, r1) = (row(y + half), row(y - half).max(row(y + half) + 1).min(height));
        for r in r0..r1 {
            for c in c0..c1 {
                let i = ((r * width + c) * 4) as usize;
                if let Some(texel) = data.get_mut(i..i + 4) {
                    texel.copy_from_slice(&rgba);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_occupied_cell_is_painted_where_it_lies_in_the_room_box() {
        let mut image = Image::new(
            Extent3d { width: 100, height: 50, depth_or_array_layers: 1 },
            TextureDimension::D2,
            vec![0; 100 * 50 * 4],
            TextureFormat::Rgba8UnormSrgb,
            RenderAssetUsages::MAIN_WORLD,
        );
        // a 2 × 1 m box at 50 texels per metre; one occupied cell 0.5 m east, 0.8 m north
        let map = CartoMap {
            cell_m: 0.02,
            cells: vec![((0.5, 0.8), Occupancy::Occupied), ((1.5, 0.2), Occupancy::Unknown)],
        };
        paint(&mut image, &map, Vec2::ZERO, Vec2::new(2.0, 1.0), 50.0);
        let data = image.data.as_ref().unwrap();
        let at = |c: usize, r: usize| &data[(r * 100 + c) * 4..(r * 100 + c) * 4 + 4];
        assert_eq!(at(25, 10), OCCUPIED_RGBA, "x 0.5 m is column 25, y 0.8 m is row 10 from the top");
        let painted = data.chunks(4).filter(|t| t[3] != 0).count();
        assert_eq!(painted, 1, "one texel for one 2 cm cell, none for an undecided one");
    }
}
