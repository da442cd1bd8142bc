//! What the headless examples (`fur.rs`, `character.rs`) share: a Bevy app without a
//! window that renders inside `update` into an image target, pelage's key light and fur
//! as Bevy components, and the readback of the target. Included by each example (and by
//! the tests that include the examples) with `#[path = "headless/mod.rs"] mod headless;`.

use std::time::Duration;

use bevy::app::{PluginGroupBuilder, PluginsState};
use bevy::camera::Exposure;
use bevy::camera::RenderTarget;
use bevy::image::Image;
use bevy::light::DirectionalLight;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::texture::GpuImage;
use bevy::render::view::{DebandDither, Msaa, Tonemapping};
use bevy::window::{ExitCondition, WindowPlugin};
use bevy_pelage::Fur;

pub type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// The frame size.
pub const WIDTH: u32 = 320;
/// The frame size.
pub const HEIGHT: u32 = 240;
/// Time between frames.
pub const FRAME_STEP: Duration = Duration::from_millis(1000 / 12);

/// Bevy's default plugins without a window, every pipeline compiled before the first
/// frame (Bevy's blit too) and the frame rendered inside `update` (so it can be read
/// right after).
pub fn plugins() -> PluginGroupBuilder {
    DefaultPlugins
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..default()
        })
        .set(RenderPlugin {
            synchronous_pipeline_compilation: true,
            ..default()
        })
        .disable::<PipelinedRenderingPlugin>()
}

/// An sRGB image target of [`WIDTH`] x [`HEIGHT`] that the examples and tests read back.
pub fn target(world: &mut World) -> Handle<Image> {
    let mut target = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba8UnormSrgb, None);
    target.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    world.resource_mut::<Assets<Image>>().add(target)
}

/// pelage's camera as a Bevy camera rendering into `image`: the same eye, target,
/// vertical field of view and near plane (Bevy's projection is reverse-Z with an
/// infinite far plane), placed by `world_from_scene`, with `msaa`, no tone mapping and
/// no dithering (pelage's own frame has neither).
pub fn camera(
    scene: &pelage::scene::Scene,
    image: &Handle<Image>,
    world_from_scene: Transform,
    msaa: Msaa,
) -> impl Bundle {
    let c = &scene.camera;
    let v3 = |v: glam::Vec3| Vec3::from_array(v.to_array());
    let local = Transform::from_translation(v3(c.eye)).looking_at(v3(c.target), Vec3::Y);
    (
        Camera3d::default(),
        RenderTarget::Image(image.clone().into()),
        Transform::from_matrix(world_from_scene.to_matrix() * local.to_matrix()),
        Projection::Perspective(PerspectiveProjection {
            fov: c.fov_y,
            near: c.near,
            ..default()
        }),
        msaa,
        Tonemapping::None,
        DebandDither::Disabled,
    )
}

/// pelage's key light (the scene's first light) as a Bevy directional light, its
/// direction turned by `rotation`: the light's direction and colour, and an illuminance
/// that the camera's default exposure brings to pelage's intensity.
pub fn key_light(
    scene: &pelage::scene::Scene,
    rotation: Quat,
) -> Result<(DirectionalLight, Transform)> {
    let Some(pelage::scene::Light::Directional(key)) = scene.lights.first() else {
        return Err("the scene's key light is not directional".into());
    };
    let direction = Vec3::from_array(key.direction.to_array());
    Ok((
        DirectionalLight {
            color: Color::linear_rgb(key.color.x, key.color.y, key.color.z),
            illuminance: key.intensity / Exposure::default().exposure(),
            ..default()
        },
        Transform::default().looking_to(rotation * direction, Vec3::Y),
    ))
}

/// The scene's hair, shading and voxel shadow as a [`Fur`] drawing the mesh, with the
/// skinned mesh's `skin_reach`.
pub fn fur(scene: &pelage::scene::Scene, skin_reach: Option<(glam::Vec3, glam::Vec3)>) -> Fur {
    Fur {
        hair: scene.hair.clone(),
        shade: scene.shade.clone(),
        voxel: match &scene.shadow {
            pelage::scene::ShadowParams::Voxel(voxel) => voxel.clone(),
            _ => Default::default(),
        },
        draw_mesh: true,
        skin_reach,
    }
}

/// Waits for the app's plugins and finishes it: ready to `update`.
pub fn finish(app: &mut App) {
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
}

/// The image the camera renders into, read back (blocking: test and example code, not
/// the plugin's frame).
pub fn read(app: &mut App, image: &Handle<Image>) -> Result<image::RgbaImage> {
    let render = app.sub_app(bevy::render::RenderApp).world();
    let gpu = pelage::gpu::Gpu::from_device(
        render.resource::<RenderDevice>().wgpu_device().clone(),
        (**render.resource::<RenderQueue>()).clone(),
        None,
    );
    let texture = &render
        .resource::<RenderAssets<GpuImage>>()
        .get(image.id())
        .ok_or("the target image is not on the GPU")?
        .texture;
    let data = pelage::gpu::read_texture(&gpu, texture)?;
    Ok(image::RgbaImage::from_raw(WIDTH, HEIGHT, data.data)
        .ok_or("the frame has the wrong size")?)
}

/// Bevy's clock after the last `update`: the time the fur (and a pose) is for.
pub fn time(app: &App) -> f32 {
    app.world().resource::<Time>().elapsed_secs()
}
