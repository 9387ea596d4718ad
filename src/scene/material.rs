//! Surface materials (Lambert + normalized Phong) and decoded textures.

use std::path::PathBuf;

use glam::Vec3;

/// A material. BRDF: f = albedo/π + specular·(n+2)/(2π)·cosⁿα with n = `shininess` and α the
/// angle between the mirror direction and the outgoing direction (normalized Phong, as in
/// Lafortune & Willems 1994, "Using the modified Phong reflectance model for physically based
/// rendering"). A material with zero `specular` is Lambertian.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// MTL name, `builtin:NAME`, or `OBJECT_NAME:override`.
    pub name: String,
    /// Diffuse reflectance ρ (MTL `Kd`), linear RGB in [0, 1].
    pub albedo: Vec3,
    /// Specular reflectance ρs (MTL `Ks`), linear RGB.
    pub specular: Vec3,
    /// Phong exponent n (MTL `Ns`), >= 0.
    pub shininess: f32,
    /// Index into [`super::Scene::textures`] of the albedo map (`map_Kd`, sRGB); it replaces
    /// `albedo` where present.
    pub albedo_texture: Option<usize>,
    /// Index into [`super::Scene::textures`] of the bump or normal map (linear).
    pub bump_texture: Option<usize>,
    pub bump_kind: BumpKind,
    /// MTL `-bm` multiplier of a height map (1 when absent).
    pub bump_scale: f32,
    /// Opacity (MTL `d`), 1 = opaque; below 1 the surface covers that fraction of the pixels
    /// and shadow-map texels (glsl/include/dissolve.glsl).
    pub opacity: f32,
}

/// How to read [`Material::bump_texture`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BumpKind {
    /// `map_bump` / `bump`: a height map (first channel).
    Height,
    /// `norm`: a tangent-space normal map (RGB = (n + 1) / 2).
    TangentNormal,
}

impl Material {
    /// A Lambertian material with the given reflectance.
    pub fn lambert(name: impl Into<String>, albedo: Vec3) -> Material {
        Material {
            name: name.into(),
            albedo,
            specular: Vec3::ZERO,
            shininess: 0.0,
            albedo_texture: None,
            bump_texture: None,
            bump_kind: BumpKind::Height,
            bump_scale: 1.0,
            opacity: 1.0,
        }
    }

    /// True when the specular lobe is absent, so Phong passes can be skipped.
    pub fn is_lambert(&self) -> bool {
        self.specular.max_element() <= 0.0
    }

    pub fn is_opaque(&self) -> bool {
        self.opacity >= 1.0
    }
}

/// A decoded texture, 8 bits per channel, RGBA, rows top to bottom.
#[derive(Clone, PartialEq)]
pub struct TextureData {
    /// The file it came from.
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba8: Vec<u8>,
    /// True for color (albedo) maps, stored sRGB-encoded; false for data (bump, normal) maps.
    pub srgb: bool,
}

impl std::fmt::Debug for TextureData {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TextureData")
            .field("path", &self.path)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("srgb", &self.srgb)
            .finish_non_exhaustive()
    }
}
