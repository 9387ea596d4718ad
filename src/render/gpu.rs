//! `Gpu*` buffer structs shared with GLSL (`glsl/include/frame.glsl`, `glsl/gbuffer.frag`),
//! each checked by the tests below against the layout reflected from every shader that
//! declares it (`vk::check_struct_against`). Each pass's push-constant struct lives with its
//! pass and is checked against the shader's reflected block when its pipeline is created.

use bytemuck::{Pod, Zeroable};

pub const MAX_LIGHTS: usize = 64;
pub const MAX_SHADOW_VIEWS: usize = 64;

pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;
/// A sample of an area light (`Light::Element`): I = intensity · max(cos θ, 0) from `direction`.
pub const LIGHT_ELEMENT: u32 = 3;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 4],
    pub direction: [f32; 4],
    pub intensity: [f32; 4],
    /// x cos(cutoff), y cutoff rad, z beam rad; w an area light's PCSS size (m, 0: none).
    pub spot: [f32; 4],
    /// x kind, y first shadow view, z shadow view count.
    pub info: [u32; 4],
}

crate::gpu_struct!(GpuLight {
    position,
    direction,
    intensity,
    spot,
    info
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuShadowView {
    pub view_proj: [f32; 16],
    /// x texel footprint (per meter of depth, meters when ortho, radians at the axis when
    /// paraboloid), y projection (`ShadowProjection::gpu_code`), z near, w far.
    pub params: [f32; 4],
    /// xyz the view's axis (cube face, paraboloid hemisphere, spot or sun direction).
    pub axis: [f32; 4],
}

crate::gpu_struct!(GpuShadowView {
    view_proj,
    params,
    axis
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuFrame {
    pub view_proj: [f32; 16],
    /// Inverse of the camera-relative view-projection (the camera at the origin): NDC to the
    /// position relative to `camera_position` (`pixel_world_position` in frame.glsl).
    pub inv_view_proj: [f32; 16],
    pub camera_position: [f32; 4],
    /// x lights, y shadow views, z width, w height.
    pub counts: [u32; 4],
    /// x constant bias (texels), y slope bias (texels), z normal offset (texels), w PCF radius.
    pub shadow: [f32; 4],
    pub lights: [GpuLight; MAX_LIGHTS],
    pub shadow_views: [GpuShadowView; MAX_SHADOW_VIEWS],
    /// The previous frame's un-jittered view-projection (this frame's in the first frame):
    /// read only by the G-buffer's motion vectors (scenes with moving objects under TAA).
    pub prev_view_proj: [f32; 16],
    /// xy: this frame's TAA jitter in NDC (0 without TAA), added to `view_proj`'s x and y.
    pub jitter_ndc: [f32; 4],
    /// xyz the camera's unit viewing direction, w the orthographic view's height in meters
    /// (0: perspective). Under orthographic projection every view ray runs along xyz
    /// (`toward_camera` etc. in frame.glsl).
    pub camera_forward: [f32; 4],
    /// The scene's environment (`glsl/include/environment.glsl`): rgb the constant's radiance
    /// or the map's scale, w the map's rotation about +Y in radians; zero without one.
    pub environment: [f32; 4],
    /// The scene's pre-exposure of half-float radiance (`scene::pre_exposure`): x 2^-k, what
    /// writers of half-float radiance multiply by; y 2^k, what their readers multiply by.
    pub radiance_scale: [f32; 4],
}

crate::gpu_struct!(GpuFrame {
    view_proj,
    inv_view_proj,
    camera_position,
    counts,
    shadow,
    lights,
    shadow_views,
    prev_view_proj,
    jitter_ndc,
    camera_forward,
    environment,
    radiance_scale
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterial {
    /// rgb albedo, a opacity.
    pub albedo: [f32; 4],
    /// rgb specular reflectance, a shininess.
    pub specular: [f32; 4],
    /// x: 1 if an albedo texture replaces `albedo` (as in the Mitsuba export); y: bump map
    /// kind; z: bump scale (f32 bits); w: the alpha map's mode (f32 bits,
    /// `scene_gpu::alpha_map_flag`, `glsl/include/alpha_map.glsl`).
    pub flags: [u32; 4],
}

crate::gpu_struct!(GpuMaterial {
    albedo,
    specular,
    flags
});

/// The GGX and emission parameters of a material, in a table of their own next to
/// [`GpuMaterial`] so that only the passes that shade them declare it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterialPbr {
    /// x roughness, y metallic, z 1 for a GGX material (0: Lambert or Phong).
    pub ggx: [f32; 4],
    /// rgb emitted radiance, W/(m²·sr).
    pub emission: [f32; 4],
    /// 1 where the draw's map replaces the value: x roughness (`map_Pr`), y metallic
    /// (`map_Pm`), z emission (`map_Ke`, multiplying the constant).
    pub maps: [u32; 4],
}

crate::gpu_struct!(GpuMaterialPbr {
    ggx,
    emission,
    maps
});

/// Interleaved vertex of every mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::check_struct_against;

    /// Every shader that declares the frame constants (through `frame.glsl`) or the
    /// materials (each declares its own copy of `GpuMaterial`) lays them out as the Rust
    /// structs do: names, offsets, sizes and array strides, read from the SPIR-V.
    #[test]
    fn buffer_structs_match_every_shader_that_declares_them() {
        for (name, _) in crate::vk::shaders::ALL {
            let Ok(i) = crate::vk::interface_of(&[name]) else {
                continue;
            };
            let check = |r: Result<(), crate::vk::VkError>| r.unwrap_or_else(|e| panic!("{e}"));
            if i.structs.contains_key("GpuFrame") {
                check(check_struct_against::<GpuFrame>(&[name], "GpuFrame"));
                check(check_struct_against::<GpuLight>(&[name], "GpuLight"));
                check(check_struct_against::<GpuShadowView>(
                    &[name],
                    "GpuShadowView",
                ));
            }
            if i.structs.contains_key("GpuMaterial") {
                check(check_struct_against::<GpuMaterial>(&[name], "GpuMaterial"));
            }
            if i.structs.contains_key("GpuMaterialPbr") {
                check(check_struct_against::<GpuMaterialPbr>(
                    &[name],
                    "GpuMaterialPbr",
                ));
            }
        }
        // The shaders named in this module's documentation and the materials' users do
        // declare them (a shader that stopped declaring them would skip the loop's checks).
        for name in ["deferred_direct.comp", "gbuffer.vert", "light_map.frag"] {
            assert!(crate::vk::interface_of(&[name])
                .unwrap()
                .structs
                .contains_key("GpuFrame"));
        }
        for name in [
            "gbuffer.frag",
            "light_map.frag",
            "shadow_depth.frag",
            "shadow_depth_paraboloid.frag",
            "gi_hemisphere.comp",
            "oit_gather.frag",
        ] {
            let i = crate::vk::interface_of(&[name]).unwrap();
            assert!(i.structs.contains_key("GpuMaterial"), "{name}");
        }
        for name in ["gbuffer.frag", "oit_gather.frag"] {
            let i = crate::vk::interface_of(&[name]).unwrap();
            assert!(i.structs.contains_key("GpuMaterialPbr"), "{name}");
        }
    }
}
