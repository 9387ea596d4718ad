//! `Gpu*` buffer structs shared with GLSL (`glsl/include/frame.glsl`, `glsl/gbuffer.frag`),
//! their std430 layouts checked by the tests below. Each pass's push-constant struct lives
//! with its pass and is checked against the shader's reflected block when its pipeline is
//! created.

use bytemuck::{Pod, Zeroable};

pub const MAX_LIGHTS: usize = 16;
pub const MAX_SHADOW_VIEWS: usize = 64;

pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 4],
    pub direction: [f32; 4],
    pub intensity: [f32; 4],
    /// x cos(cutoff), y cutoff rad, z beam rad.
    pub spot: [f32; 4],
    /// x kind, y first shadow view, z shadow view count.
    pub info: [u32; 4],
}

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

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuFrame {
    pub view_proj: [f32; 16],
    pub inv_view_proj: [f32; 16],
    pub camera_position: [f32; 4],
    /// x lights, y shadow views, z width, w height.
    pub counts: [u32; 4],
    /// x constant bias (texels), y slope bias (texels), z normal offset (texels), w PCF radius.
    pub shadow: [f32; 4],
    pub lights: [GpuLight; MAX_LIGHTS],
    pub shadow_views: [GpuShadowView; MAX_SHADOW_VIEWS],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterial {
    /// rgb albedo, a opacity.
    pub albedo: [f32; 4],
    /// rgb specular reflectance, a shininess.
    pub specular: [f32; 4],
    /// x: 1 if an albedo texture replaces `albedo` (as in the Mitsuba export).
    pub flags: [u32; 4],
}

/// The GGX and emission parameters of a material, in a table of their own next to
/// [`GpuMaterial`] so that only the passes that shade them declare it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterialPbr {
    /// x roughness, y metallic, z 1 for a GGX material (0: Lambert or Phong).
    pub ggx: [f32; 4],
    /// rgb emitted radiance, W/(m²·sr).
    pub emission: [f32; 4],
}

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
    use std::mem::{offset_of, size_of};

    #[test]
    fn layouts_match_std430() {
        // std430: vec4/uvec4 16 bytes, mat4 64, struct arrays stride = struct size (x16).
        assert_eq!(size_of::<GpuLight>(), 80);
        assert_eq!(offset_of!(GpuLight, info), 64);
        assert_eq!(size_of::<GpuShadowView>(), 96);
        assert_eq!(offset_of!(GpuShadowView, params), 64);
        assert_eq!(offset_of!(GpuFrame, inv_view_proj), 64);
        assert_eq!(offset_of!(GpuFrame, camera_position), 128);
        assert_eq!(offset_of!(GpuFrame, counts), 144);
        assert_eq!(offset_of!(GpuFrame, shadow), 160);
        assert_eq!(offset_of!(GpuFrame, lights), 176);
        assert_eq!(offset_of!(GpuFrame, shadow_views), 176 + 80 * MAX_LIGHTS);
        assert_eq!(
            size_of::<GpuFrame>(),
            176 + 80 * MAX_LIGHTS + 96 * MAX_SHADOW_VIEWS
        );
        assert_eq!(size_of::<GpuMaterial>(), 48);
        assert_eq!(offset_of!(GpuMaterial, flags), 32);
        assert_eq!(size_of::<GpuMaterialPbr>(), 32);
        assert_eq!(offset_of!(GpuMaterialPbr, emission), 16);
        assert_eq!(size_of::<GpuVertex>(), 32);
        assert_eq!(offset_of!(GpuVertex, uv), 24);
    }
}
