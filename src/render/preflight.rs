//! What a renderer refuses before it allocates anything: settings that do not combine, a
//! camera the GI method cannot render, more lights or shadow views than a frame holds, and a
//! voxel grid or frame that does not fit the device.

use super::gpu::{MAX_LIGHTS, MAX_SHADOW_VIEWS};
use super::{memory, RenderError, RenderSettings};
use crate::light::{area::frame_lights, shadow_views};
use crate::scene::Scene;
use crate::vk::{vk, BufferDesc, Context, ImageDesc, MemoryLocation};

/// Refuses what an orthographic camera cannot render: screen-space GI, whose patch areas
/// (Oetke 2017, Eq. 2.10: z² times a pinhole's texel solid angle), reflection march (linear in
/// 1/w) and history (clip w as depth) assume a pinhole camera, and stereo pairs, whose
/// off-axis frusta are a perspective concept.
/// `Renderer::new` and every `prepare` run it (the viewer switches projection per frame).
pub fn check_projection(
    camera: &crate::scene::Camera,
    settings: &RenderSettings,
    stereo: bool,
) -> Result<(), RenderError> {
    if !camera.is_orthographic() {
        return Ok(());
    }
    if stereo {
        return Err(RenderError::Orthographic {
            what: "--stereo",
            why: "a stereo pair's eyes are off-axis perspective frusta",
            instead: "leave out --stereo",
        });
    }
    if let Some(r) = settings.gi.method.spec().orthographic_blocker {
        if settings.debug.is_none() {
            return Err(RenderError::Orthographic {
                what: r.what,
                why: r.why,
                instead: r.instead,
            });
        }
    }
    Ok(())
}

/// Refuses a voxel grid that cannot fit the device, before anything is allocated: its column
/// image (all mips) and the column buffer of its mip 0.
pub(super) fn check_voxel_memory(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    voxels: &crate::voxel::gpu::VoxelSettings,
) -> Result<(), RenderError> {
    let grid = voxels
        .grid_for(scene, settings.time_s)
        .map_err(crate::voxel::gpu::GpuVoxelError::from)?;
    let image = crate::voxel::gpu::column_image_desc(&grid);
    let buffer = BufferDesc {
        name: "voxel column buffer".into(),
        size_bytes: crate::voxel::gpu::column_bytes(&grid),
        usage: vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuOnly,
    };
    memory::check_fits(
        ctx,
        &format!(
            "the voxel grid of {}×{} columns × {} layer(s)",
            grid.res_x(),
            grid.res_y(),
            grid.layers()
        ),
        "--voxels or --voxel-layers (the scene's `[voxel] resolution` or `layers`)",
        &[
            memory::MemoryNeed::image(ctx, &image),
            memory::MemoryNeed::buffer(ctx, &buffer),
        ],
        ctx.allocated_bytes(),
    )
}

/// The read-back buffers of a `w`×`h` frame: linear RGBA32F radiance and RGBA8 LDR.
pub(super) fn readback_descs((w, h): (u32, u32)) -> [BufferDesc; 2] {
    let pixels = u64::from(w) * u64::from(h);
    let desc = |name: &str, bytes_per_pixel: u64| BufferDesc {
        name: name.into(),
        size_bytes: pixels * bytes_per_pixel,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuToCpu,
    };
    [desc("readback hdr", 16), desc("readback ldr", 4)]
}

/// What sizes a frame, for memory errors.
pub(super) fn frame_subject(s: &RenderSettings) -> String {
    format!("the {}×{} frame", s.width, s.height)
}
pub(super) const FRAME_FLAGS: &str = "--width/--height";

/// Refuses a frame whose persistent frame-sized resources (read-back buffers, the TAA, path
/// tracer and SSGI histories) cannot fit the device, before anything is allocated. The
/// transients are checked by [`check_transient_memory`] once the passes exist.
pub(super) fn check_frame_memory(
    ctx: &Context,
    scene: &Scene,
    s: &RenderSettings,
    gi_on: bool,
    eyes: u32,
) -> Result<(), RenderError> {
    memory::check_fits(
        ctx,
        &frame_subject(s),
        FRAME_FLAGS,
        &frame_memory_needs(ctx, scene, s, gi_on, eyes),
        ctx.allocated_bytes(),
    )
}

/// The persistent frame-sized resources of a frame (read-back buffers, the TAA, path tracer
/// and SSGI histories), per eye.
pub(super) fn frame_memory_needs(
    ctx: &Context,
    scene: &Scene,
    s: &RenderSettings,
    gi_on: bool,
    eyes: u32,
) -> Vec<memory::MemoryNeed> {
    let size = (s.width, s.height);
    let mut needs: Vec<_> = readback_descs(size)
        .iter()
        .map(|d| memory::MemoryNeed::buffer(ctx, d))
        .collect();
    let mut images = Vec::new();
    for _ in 0..eyes.max(1) {
        per_eye_frame_images(scene, s, gi_on, &mut images);
    }
    if eyes > 1 {
        needs.extend(needs.clone());
    }
    needs.extend(images.iter().map(|d| memory::MemoryNeed::image(ctx, d)));
    needs
}

/// The persistent frame-sized images of one eye (TAA, path tracer and SSGI histories).
fn per_eye_frame_images(
    scene: &Scene,
    s: &RenderSettings,
    gi_on: bool,
    images: &mut Vec<ImageDesc>,
) {
    let size = (s.width, s.height);
    if s.debug.is_none() && s.post.taa.is_some() {
        images.push(crate::post::TaaPass::history_desc(size));
    }
    if gi_on {
        let glossy = scene.has_phong() || scene.has_ggx();
        images.extend(crate::gi::GiPasses::frame_image_descs(&s.gi, size, glossy));
    }
}

/// Whether `settings` combine at all, independent of scene and device: the combination a
/// renderer refuses (SAO without GI; every GI method renders with paraboloid point
/// shadows and with area lights). [`Renderer::new`] runs it first; `voxgi sweep` asks it to
/// leave such configurations out instead of failing on them.
pub fn check_setting_combination(settings: &RenderSettings) -> Result<(), RenderError> {
    use crate::gi::GiMethod;
    let gi_on = settings.gi.method != GiMethod::None && settings.debug.is_none();
    if !gi_on && settings.gi.sao.is_some() {
        return Err(RenderError::SaoWithoutGi);
    }
    Ok(())
}

/// Refuses lights a frame cannot hold: more than [`MAX_LIGHTS`] (an area light counts its
/// samples) or more than [`MAX_SHADOW_VIEWS`] shadow views with the directional lights'
/// cascades, the checks of [`Renderer::new`] and [`Renderer::prepare`]. The viewer's editor
/// asks before it adds a light.
pub fn check_lights(scene: &Scene, settings: &RenderSettings) -> Result<(), RenderError> {
    let lights = frame_lights(&scene.lights, &settings.shadow);
    if lights.len() > MAX_LIGHTS {
        return Err(RenderError::TooManyLights(lights.len()));
    }
    let (views, _) = shadow_views(scene, settings.time_s, &settings.shadow);
    let capacity = match settings.shadow.cascades {
        n if n >= 2 => n as usize * lights.iter().filter(|l| l.is_directional()).count(),
        _ => 0,
    };
    if views.len() + capacity > MAX_SHADOW_VIEWS {
        return Err(RenderError::TooManyShadowViews(views.len() + capacity));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::PointShadow;

    /// The lights a frame holds: 64 lights, 64 shadow views (a cube-shadowed point light takes
    /// 6, so 10 fit and 11 do not; with paraboloid shadows 2 each, 32 fit).
    #[test]
    fn check_lights_counts_lights_and_shadow_views() {
        let mut scene = crate::scene::builtin("cornell-point").expect("cornell-point");
        let point = scene.lights[0];
        let settings = RenderSettings::default();
        scene.lights = vec![point; 10];
        assert!(check_lights(&scene, &settings).is_ok());
        scene.lights.push(point);
        assert!(matches!(
            check_lights(&scene, &settings),
            Err(RenderError::TooManyShadowViews(66))
        ));
        let mut paraboloid = settings.clone();
        paraboloid.shadow.point_technique = PointShadow::DualParaboloid;
        assert!(check_lights(&scene, &paraboloid).is_ok());
        scene.lights = vec![point; 65];
        assert!(matches!(
            check_lights(&scene, &paraboloid),
            Err(RenderError::TooManyLights(65))
        ));
    }
}
