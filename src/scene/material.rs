//! Surface materials (Lambert, normalized Phong, GGX metal/roughness, emission) and decoded
//! textures.

use std::path::PathBuf;

use glam::Vec3;

/// A material. BRDF: f = albedo/π + specular·(n+2)/(2π)·cosⁿα with n = `shininess` and α the
/// angle between the mirror direction and the outgoing direction (normalized Phong, as in
/// Lafortune & Willems 1994, "Using the modified Phong reflectance model for physically based
/// rendering"). A material with zero `specular` is Lambertian. A material with [`Material::ggx`]
/// uses the metal/roughness BRDF of [`ggx_brdf`] instead (its `specular` and `shininess` are
/// ignored). Any material may emit ([`Material::emission`]).
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
    /// GGX metal/roughness parameters (MTL `Pr`/`Pm`, TOML `roughness`/`metallic`); `None` for
    /// Lambert and Phong materials. `albedo` is then the base color.
    pub ggx: Option<Ggx>,
    /// Emitted radiance L_e (MTL `Ke`, TOML `emission_w_sr_m2`) in W/(m²·sr), linear RGB,
    /// leaving the front side (the side the normals point to, as Mitsuba's `area` emitter).
    pub emission: Vec3,
}

/// Metal/roughness parameters of the GGX BRDF ([`ggx_brdf`]), each in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Perceptual roughness r; the GGX width is α = r².
    pub roughness: f32,
    /// 0 = dielectric (F0 = 0.04, diffuse base color), 1 = metal (F0 = base color, no diffuse).
    pub metallic: f32,
}

/// Normal-incidence Fresnel reflectance of dielectrics in the metal/roughness workflow (an
/// index of refraction of 1.5).
pub const DIELECTRIC_F0: f32 = 0.04;

/// Schlick's Fresnel approximation F(c) = F0 + (1 − F0)(1 − c)⁵.
pub fn fresnel_schlick(f0: Vec3, cos: f32) -> Vec3 {
    f0 + (Vec3::ONE - f0) * (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

/// GGX (Trowbridge-Reitz) normal distribution D(h) = α² / (π ((n·h)²(α² − 1) + 1)²).
pub fn ggx_d(alpha: f32, n_dot_h: f32) -> f32 {
    let a2 = alpha * alpha;
    let t = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    a2 / (std::f32::consts::PI * t * t)
}

/// Exact Smith masking of GGX for one direction, G1(v) = 2 (n·v) / ((n·v) + √(α² + (1 − α²)(n·v)²))
/// (= 2 / (1 + √(1 + α² tan²θ)), the form Mitsuba's microfacet distribution evaluates).
pub fn ggx_g1(alpha: f32, n_dot_v: f32) -> f32 {
    let a2 = alpha * alpha;
    let c = n_dot_v.max(0.0);
    2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt()).max(1e-30)
}

/// The GGX metal/roughness BRDF f(wi, wo) (1/sr, without the cosine), every vector unit length:
///
/// f = (1 − m)·base/π·(1 − F_d(n·wi))(1 − F_d(n·wo)) + D(h)·G1(wi)·G1(wo)·F(wo·h) / (4 (n·wi)(n·wo))
///
/// with α = roughness², h = normalize(wi + wo), D GGX ([`ggx_d`]), G the separable exact
/// Smith-GGX masking-shadowing ([`ggx_g1`], as Mitsuba's `roughconductor` and `principled`),
/// F Schlick ([`fresnel_schlick`]) with F0 = mix(0.04, base, m), and F_d Schlick with F0 = 0.04.
/// The diffuse lobe's (1 − F_d)(1 − F_d) weighting (reciprocal, as the diffuse term of Mitsuba's
/// `roughplastic`) keeps a white dielectric from gaining energy at grazing angles; no
/// multiple-scattering compensation is applied, so rough surfaces lose some energy
/// (single-scattering GGX).
pub fn ggx_brdf(base: Vec3, ggx: Ggx, n: Vec3, wi: Vec3, wo: Vec3) -> Vec3 {
    let (ci, co) = (n.dot(wi), n.dot(wo));
    if ci <= 0.0 || co <= 0.0 {
        return Vec3::ZERO;
    }
    let alpha = ggx.roughness * ggx.roughness;
    let h = (wi + wo).normalize();
    let f0 = Vec3::splat(DIELECTRIC_F0).lerp(base, ggx.metallic);
    let specular = fresnel_schlick(f0, wo.dot(h))
        * ggx_d(alpha, n.dot(h))
        * ggx_g1(alpha, ci)
        * ggx_g1(alpha, co)
        / (4.0 * ci * co);
    let fd = |c: f32| 1.0 - fresnel_schlick(Vec3::splat(DIELECTRIC_F0), c).x;
    let diffuse = base * ((1.0 - ggx.metallic) * fd(ci) * fd(co) / std::f32::consts::PI);
    diffuse + specular
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
            ggx: None,
            emission: Vec3::ZERO,
        }
    }

    /// True when the material is Lambert (no Phong lobe, not GGX), so Phong passes can be
    /// skipped.
    pub fn is_lambert(&self) -> bool {
        self.ggx.is_none() && self.specular.max_element() <= 0.0
    }

    /// True when the material has a normalized-Phong lobe.
    pub fn is_phong(&self) -> bool {
        self.ggx.is_none() && self.specular.max_element() > 0.0
    }

    /// True when some channel of [`Material::emission`] is positive.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
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
