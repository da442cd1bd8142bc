//! Bevy's mesh UVs feed pelage's texture maps: on Bevy's own UV sphere (its `v` = 0 pole
//! turned to the top of the picture), a density map black in its top half grows fur only
//! on the lower half of the sphere, and the same map upside down only on the upper
//! half, drawn by the plugin (fur only: pelage does not draw the mesh).

#[allow(dead_code)]
#[path = "../examples/headless/mod.rs"]
mod headless;

use std::f32::consts::FRAC_PI_2;

use bevy::prelude::*;
use bevy::render::view::Msaa;
use bevy::time::TimeUpdateStrategy;
use bevy_pelage::PelagePlugin;
use pelage::scene::{MapImage, TextureMap};

/// A 1 x 64 density map: black (no fur) in its top half, white in its bottom half, or
/// the other way round.
fn half_map(black_top: bool) -> TextureMap {
    let texels = (0..64)
        .map(|row| {
            let white = (row >= 32) == black_top;
            if white { [255; 4] } else { [0, 0, 0, 255] }
        })
        .collect();
    let name = if black_top {
        "black top"
    } else {
        "black bottom"
    };
    TextureMap::from_image(name, MapImage::new(1, 64, texels).unwrap())
}

/// Fur pixels (not the background) in the top and bottom halves of the plugin's frame
/// of Bevy's UV sphere with `density` as its density map.
fn fur_halves(density: Option<TextureMap>) -> (usize, usize) {
    let mut scene = pelage::scene::Scene::default();
    scene.camera = pelage::scene::Camera {
        eye: glam::Vec3::new(0.0, 0.0, 2.6),
        target: glam::Vec3::ZERO,
        ..Default::default()
    };
    let mut app = App::new();
    app.add_plugins(headless::plugins())
        .add_plugins(PelagePlugin)
        .insert_resource(TimeUpdateStrategy::ManualDuration(headless::FRAME_STEP));
    let bg = scene.shade.background;
    app.insert_resource(ClearColor(Color::linear_rgb(bg.x, bg.y, bg.z)));
    let world = app.world_mut();
    let image = headless::target(world);
    // Bevy's UV sphere: v = 0 at its +Z pole (the top of a texture).
    let sphere = world
        .resource_mut::<Assets<Mesh>>()
        .add(Sphere::new(0.5).mesh().uv(48, 24));
    world.spawn(headless::camera(
        &scene,
        &image,
        Transform::default(),
        Msaa::default(),
    ));
    world.spawn(headless::key_light(&scene, Quat::IDENTITY).unwrap());
    let mut fur = headless::fur(&scene, None);
    fur.draw_mesh = false;
    fur.hair.roots.count = 6000;
    fur.hair.roots.textures.density = density;
    world.spawn((
        Mesh3d(sphere),
        fur,
        // The +Z pole (v = 0) up.
        Transform::from_rotation(Quat::from_rotation_x(-FRAC_PI_2)),
    ));
    headless::finish(&mut app);
    for _ in 0..3 {
        app.update();
    }
    let frame = headless::read(&mut app, &image).unwrap();
    let background = *frame.get_pixel(0, 0);
    let half = frame.height() / 2;
    let count = |rows: std::ops::Range<u32>| {
        rows.flat_map(|y| (0..frame.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| *frame.get_pixel(x, y) != background)
            .count()
    };
    (count(0..half), count(half..frame.height()))
}

#[test]
fn a_density_map_grows_fur_where_bevys_uvs_say() {
    let (top, bottom) = fur_halves(None);
    println!("no map: {top} fur pixels in the top half, {bottom} in the bottom half");
    assert!(top > 2000 && bottom > 2000, "{top} / {bottom}");
    let (top_a, bottom_a) = fur_halves(Some(half_map(true)));
    println!("black top: {top_a} fur pixels in the top half, {bottom_a} in the bottom half");
    let (top_b, bottom_b) = fur_halves(Some(half_map(false)));
    println!("black bottom: {top_b} fur pixels in the top half, {bottom_b} in the bottom half");
    // Strands rooted just below the equator reach a little over it: the bare half keeps
    // at most a tenth of the furred half's pixels.
    assert!(
        top_a * 10 < bottom_a,
        "black top: {top_a} top, {bottom_a} bottom"
    );
    assert!(
        bottom_b * 10 < top_b,
        "black bottom: {top_b} top, {bottom_b} bottom"
    );
}
