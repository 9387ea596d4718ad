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
    /// The MTL PBR maps (`map_Pr`, `map_Pm`, `map_Ke`), indices into
    /// [`super::Scene::textures`].
    pub pbr_maps: PbrMaps,
    /// Per-texel alpha (glTF base colour alpha, MTL `map_d`), `None` for the constant
    /// `opacity` alone.
    pub alpha_map: Option<AlphaMap>,
}

/// A material's per-texel alpha: the alpha channel of one texture, which is the albedo texture
/// itself when the material has one (loaders merge an MTL `map_d` into a copy of `map_Kd`), so
/// that every pass that samples the albedo map reads the alpha with the same lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaMap {
    /// Index into [`super::Scene::textures`]; equal to [`Material::albedo_texture`] when that
    /// is set (the invariant [`Material::draw_texture`] relies on).
    pub texture: usize,
    pub mode: AlphaMode,
}

/// How the alpha of an [`AlphaMap`] acts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// A cutout (glTF `MASK`, MTL `map_d`): the surface exists where the texel's alpha is at
    /// least the cutoff (in (0, 1]) and is absent elsewhere, in every pass that draws it.
    Cutout(f32),
    /// Per-texel opacity (glTF `BLEND`): `opacity` × texel alpha, drawn by the transparency
    /// path (OIT or hashed) as a constant opacity is.
    Blend,
}

/// Texture maps of the GGX parameters and of the emission (MTL PBR extension), read by the
/// G-buffer. `roughness` and `metallic` (`map_Pr`, `map_Pm`: linear, first channel) replace
/// the constants where present, as `map_Kd` replaces `Kd`; `emission` (`map_Ke`, sRGB) is
/// multiplied by `Ke` (1 when the MTL gives only the map), so that an 8-bit map can scale a
/// radiance above 1 W/(m²·sr). The voxel volumes take each map's mean instead
/// ([`Material::voxel_ggx`], [`Material::voxel_emission`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PbrMaps {
    pub roughness: Option<usize>,
    pub metallic: Option<usize>,
    pub emission: Option<usize>,
}

impl PbrMaps {
    /// The maps in the G-buffer's binding order (roughness, metallic, emission).
    pub fn as_array(&self) -> [Option<usize>; 3] {
        [self.roughness, self.metallic, self.emission]
    }
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
    let f0 = Vec3::splat(DIELECTRIC_F0).lerp_monotonic(base, ggx.metallic);
    let diffuse = base * (1.0 - ggx.metallic);
    ggx_diffuse(diffuse, n, wi, wo) + ggx_specular(f0, ggx.roughness, n, wi, wo)
}

/// The diffuse lobe of [`ggx_brdf`], `diffuse`/π·(1 − F_d(n·wi))(1 − F_d(n·wo)).
pub fn ggx_diffuse(diffuse: Vec3, n: Vec3, wi: Vec3, wo: Vec3) -> Vec3 {
    let (ci, co) = (n.dot(wi), n.dot(wo));
    if ci <= 0.0 || co <= 0.0 {
        return Vec3::ZERO;
    }
    let fd = |c: f32| 1.0 - fresnel_schlick(Vec3::splat(DIELECTRIC_F0), c).x;
    diffuse * (fd(ci) * fd(co) / std::f32::consts::PI)
}

/// The specular lobe of [`ggx_brdf`], D(h)·G1(wi)·G1(wo)·F(wo·h) / (4 (n·wi)(n·wo)), α = roughness².
pub fn ggx_specular(f0: Vec3, roughness: f32, n: Vec3, wi: Vec3, wo: Vec3) -> Vec3 {
    let (ci, co) = (n.dot(wi), n.dot(wo));
    if ci <= 0.0 || co <= 0.0 {
        return Vec3::ZERO;
    }
    let alpha = roughness * roughness;
    let h = (wi + wo).normalize();
    fresnel_schlick(f0, wo.dot(h))
        * (ggx_d(alpha, n.dot(h)) * ggx_g1(alpha, ci) * ggx_g1(alpha, co) / (4.0 * ci * co))
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
            pbr_maps: PbrMaps::default(),
            alpha_map: None,
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

    /// True when MTL `d` (or `opacity`) is 1 and no texel blends: the surface hides what is
    /// behind it (where a cutout leaves it).
    pub fn is_opaque(&self) -> bool {
        self.opacity >= 1.0
            && !matches!(
                self.alpha_map,
                Some(AlphaMap {
                    mode: AlphaMode::Blend,
                    ..
                })
            )
    }

    /// The cutoff of a cutout alpha map, `None` without one.
    pub fn alpha_cutoff(&self) -> Option<f32> {
        match self.alpha_map {
            Some(AlphaMap {
                mode: AlphaMode::Cutout(c),
                ..
            }) => Some(c),
            _ => None,
        }
    }

    /// The texture the passes bind for a draw of this material: the albedo map, or the alpha
    /// map of a material without one (whose `flags.x` keeps the constant albedo).
    pub fn draw_texture(&self) -> Option<usize> {
        self.albedo_texture.or(self.alpha_map.map(|a| a.texture))
    }

    /// The fraction of the surface that the binary voxel grid should keep: `opacity`, times
    /// the fraction of texels whose alpha passes the cutoff (a cutout) or the mean texel alpha
    /// (blend). A voxel spans many texels, so the voxelizers take this mean through the
    /// stochastic coverage of `voxel::coverage` rather than testing texels.
    pub fn coverage_opacity(&self, textures: &[TextureData]) -> f32 {
        let Some(map) = self.alpha_map else {
            return self.opacity;
        };
        let Some(t) = textures.get(map.texture) else {
            return self.opacity;
        };
        let n = (t.rgba8.len() / 4).max(1) as f64;
        let mean = match map.mode {
            AlphaMode::Cutout(c) => {
                let open = t
                    .rgba8
                    .chunks_exact(4)
                    .filter(|p| f32::from(p[3]) / 255.0 >= c)
                    .count();
                open as f64 / n
            }
            AlphaMode::Blend => {
                t.rgba8
                    .chunks_exact(4)
                    .map(|p| f64::from(p[3]))
                    .sum::<f64>()
                    / (255.0 * n)
            }
        };
        self.opacity * mean as f32
    }

    /// The GGX parameters the voxel volumes take: a `map_Pr` / `map_Pm` replaced by the mean
    /// of its first channel (a voxel covers many texels; the G-buffer samples the map itself).
    pub fn voxel_ggx(&self, textures: &[TextureData]) -> Option<Ggx> {
        let mean = |map: Option<usize>, constant: f32| {
            map.and_then(|t| textures.get(t))
                .map_or(constant, |t| t.mean_linear.x)
        };
        self.ggx.map(|g| Ggx {
            roughness: mean(self.pbr_maps.roughness, g.roughness),
            metallic: mean(self.pbr_maps.metallic, g.metallic),
        })
    }

    /// The emitted radiance the voxel volumes take, W/(m²·sr): `Ke` times the mean linear
    /// color of `map_Ke` when there is one.
    pub fn voxel_emission(&self, textures: &[TextureData]) -> Vec3 {
        self.pbr_maps
            .emission
            .and_then(|t| textures.get(t))
            .map_or(self.emission, |t| self.emission * t.mean_linear)
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
    /// The mean of the texels in linear RGB (sRGB maps decoded first), computed once by
    /// [`TextureData::new`]; the voxel volumes take it in place of the map.
    pub mean_linear: Vec3,
}

impl TextureData {
    /// A texture of `width * height` RGBA texels, `rgba8` row by row, with its mean.
    pub fn new(path: PathBuf, width: u32, height: u32, rgba8: Vec<u8>, srgb: bool) -> TextureData {
        let mean_linear = mean_linear_rgb(&rgba8, srgb);
        TextureData {
            path,
            width,
            height,
            rgba8,
            srgb,
            mean_linear,
        }
    }

    /// RGBA8 mip chain down to 1×1 (box filter, sRGB channels averaged as light); level 0 is
    /// the texture itself. The G-buffer's textures and the voxelizers' maps
    /// (`voxel::maps`) use the same levels.
    pub fn mip_chain(&self) -> Vec<Vec<u8>> {
        let (mut w, mut h) = (self.width.max(1), self.height.max(1));
        let mut levels = vec![self.rgba8.clone()];
        while w > 1 || h > 1 {
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let prev = &levels[levels.len() - 1];
            let mut next = vec![0u8; (nw * nh * 4) as usize];
            for y in 0..nh {
                for x in 0..nw {
                    for c in 0..4 {
                        let mut sum = 0.0f32;
                        let mut n = 0.0f32;
                        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                            let v = f32::from(prev[((sy * w + sx) * 4 + c) as usize]) / 255.0;
                            // Average light, not encoded values: decode sRGB color channels first.
                            sum += if self.srgb && c < 3 {
                                crate::imaging::srgb_decode(v)
                            } else {
                                v
                            };
                            n += 1.0;
                        }
                        let avg = sum / n;
                        let enc = if self.srgb && c < 3 {
                            crate::imaging::srgb_encode(avg)
                        } else {
                            avg
                        };
                        next[((y * nw + x) * 4 + c) as usize] =
                            (enc.clamp(0.0, 1.0) * 255.0).round() as u8;
                    }
                }
            }
            levels.push(next);
            (w, h) = (nw, nh);
        }
        levels
    }
}

/// The mean linear RGB of RGBA8 texels (alpha ignored); sRGB codes are decoded before
/// averaging, as a filtered lookup of an sRGB texture averages light, not codes.
fn mean_linear_rgb(rgba8: &[u8], srgb: bool) -> Vec3 {
    let decode: Vec<f64> = (0..=255u8)
        .map(|c| {
            let v = f32::from(c) / 255.0;
            f64::from(if srgb {
                crate::imaging::srgb_decode(v)
            } else {
                v
            })
        })
        .collect();
    let mut sum = [0.0f64; 3];
    let mut n = 0usize;
    for p in rgba8.chunks_exact(4) {
        for (s, &c) in sum.iter_mut().zip(p) {
            *s += decode[usize::from(c)];
        }
        n += 1;
    }
    if n == 0 {
        return Vec3::ZERO;
    }
    Vec3::from_array(sum.map(|s| (s / n as f64) as f32))
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const N: Vec3 = Vec3::Y;

    /// Unit vector at polar angle `theta` from +y, azimuth `phi`.
    fn dir(theta: f64, phi: f64) -> Vec3 {
        let (st, ct) = theta.sin_cos();
        Vec3::new((st * phi.cos()) as f32, ct as f32, (st * phi.sin()) as f32)
    }

    /// ∫ g(h) dω_h over the upper hemisphere by the midpoint rule in the variables that make
    /// D(h) cosθ_h uniform (tan²θ_h = α² t / (1 − t), φ = 2πs), so that sharp lobes are
    /// resolved: dω_h = dt ds / (D(h) cosθ_h). The weight 1/cosθ_h diverges like 1/√(1 − t)
    /// at the horizon, so t = 1 − u² (dt = 2u du) makes the integrand bounded.
    fn integrate_h(alpha: f32, g: impl Fn(Vec3) -> f64) -> f64 {
        let (nt, ns) = (1000, 64);
        let mut sum = 0.0;
        for i in 0..nt {
            let u = (i as f64 + 0.5) / nt as f64;
            let t = 1.0 - u * u;
            let theta = (f64::from(alpha) * (t / (1.0 - t)).sqrt()).atan();
            for j in 0..ns {
                let h = dir(theta, 2.0 * PI * (j as f64 + 0.5) / ns as f64);
                let pdf = f64::from(ggx_d(alpha, h.y)) * f64::from(h.y);
                sum += 2.0 * u * g(h) / pdf;
            }
        }
        sum / (nt * ns) as f64
    }

    /// ∫ g(wi) cosθ_i dω_i over the upper hemisphere (midpoint rule in cos²θ and φ).
    fn integrate_cosine(g: impl Fn(Vec3) -> f64) -> f64 {
        let (nu, np) = (400, 128);
        let mut sum = 0.0;
        for i in 0..nu {
            let u = (i as f64 + 0.5) / nu as f64;
            for j in 0..np {
                sum += g(dir(
                    u.sqrt().acos(),
                    2.0 * PI * (j as f64 + 0.5) / np as f64,
                ));
            }
        }
        // cosθ dω = (1/2) d(cos²θ) dφ.
        sum * PI / (nu * np) as f64
    }

    /// Directional albedo ∫ f(wi, wo) cosθ_i dω_i of the white (F0 = `f0`) specular lobe, in
    /// half-vector space: wi = reflect(−wo, h), dω_i = 4 (wo·h) dω_h.
    fn specular_albedo(f0: f32, roughness: f32, wo: Vec3) -> f64 {
        integrate_h(roughness * roughness, |h| {
            let wi = 2.0 * wo.dot(h) * h - wo;
            let f = ggx_specular(Vec3::splat(f0), roughness, N, wi, wo).x;
            f64::from(f * wi.y.max(0.0) * 4.0 * wo.dot(h).max(0.0))
        })
    }

    fn diffuse_albedo(wo: Vec3) -> f64 {
        integrate_cosine(|wi| f64::from(ggx_diffuse(Vec3::ONE, N, wi, wo).x))
    }

    const ROUGHNESS: [f32; 5] = [0.1, 0.25, 0.5, 0.75, 1.0];
    const THETA_O_DEG: [f64; 5] = [0.0, 30.0, 60.0, 80.0, 89.0];

    #[test]
    fn ggx_d_and_smith_g1_satisfy_their_normalizations() {
        // Closed forms (Heitz 2014, "Understanding the masking-shadowing function", eq. 4 and
        // 17): ∫ D(h) cosθ_h dω_h = 1, and Smith's G1 makes the projected microfacet area
        // equal the projected macro area, ∫ G1(wo) max(0, wo·h) D(h) dω_h = cosθ_o.
        for r in ROUGHNESS {
            let alpha = r * r;
            let area = integrate_h(alpha, |h| f64::from(ggx_d(alpha, h.y) * h.y));
            assert!((area - 1.0).abs() < 1e-3, "r {r}: ∫D cos = {area}");
            for t in THETA_O_DEG {
                let wo = dir(t.to_radians(), 0.3);
                let g1 = f64::from(ggx_g1(alpha, wo.y));
                let projected = integrate_h(alpha, |h| {
                    g1 * f64::from(wo.dot(h).max(0.0) * ggx_d(alpha, h.y))
                });
                let want = f64::from(wo.y);
                assert!(
                    // The midpoint rule's error at the kink of max(0, wo·h): below 0.5%.
                    (projected - want).abs() < 5e-3 * want.max(0.05),
                    "r {r}, θo {t}°: {projected} vs cosθo {want}"
                );
            }
        }
    }

    #[test]
    fn ggx_at_normal_incidence_matches_the_closed_form() {
        // wi = wo = n: h = n, D = 1/(π α²), G1 = 1, F = F0, F_d = 0.04:
        // f = F0/(4π α²) + (1 − m) base (0.96)²/π.
        let base = Vec3::new(0.9, 0.5, 0.2);
        for (r, m) in [(0.3, 0.0), (0.6, 1.0), (1.0, 0.4)] {
            let f = ggx_brdf(
                base,
                Ggx {
                    roughness: r,
                    metallic: m,
                },
                N,
                N,
                N,
            );
            let alpha = r * r;
            let f0 = Vec3::splat(DIELECTRIC_F0).lerp_monotonic(base, m);
            let pi = std::f32::consts::PI;
            let want = f0 / (4.0 * pi * alpha * alpha) + (1.0 - m) * base * 0.96 * 0.96 / pi;
            assert!(
                (f - want).abs().max_element() < 1e-5 * want.max_element(),
                "{f} vs {want}"
            );
        }
    }

    #[test]
    fn white_furnace_ggx_never_gains_energy() {
        // A white metal (F0 = 1) and a white dielectric (base 1, m = 0) in uniform unit
        // radiance reflect their directional albedo; neither may exceed 1. Single-scattering
        // GGX loses energy as roughness grows (no multiple-scattering compensation).
        let mut loss_r1 = Vec::new();
        for r in ROUGHNESS {
            for t in THETA_O_DEG {
                let wo = dir(t.to_radians(), 0.0);
                let metal = specular_albedo(1.0, r, wo);
                let dielectric = specular_albedo(DIELECTRIC_F0, r, wo) + diffuse_albedo(wo);
                assert!(
                    metal <= 1.0 + 2e-3,
                    "white metal r {r}, θo {t}°: albedo {metal}"
                );
                assert!(
                    dielectric <= 1.0 + 2e-3,
                    "white dielectric r {r}, θo {t}°: albedo {dielectric}"
                );
                if r == 1.0 {
                    loss_r1.push((t, 1.0 - metal, 1.0 - dielectric));
                }
            }
        }
        // Closed form at α = 1, wo = n: D = 1/π, G1(wi) = cos2θ_h / cos²θ_h for wi at
        // 2θ_h < 90°, so the albedo is ∫₀^{π/4} 2 cos2θ tanθ dθ = 1 − ln 2.
        let rough = specular_albedo(1.0, 1.0, N);
        let want = 1.0 - std::f64::consts::LN_2;
        assert!(
            (rough - want).abs() < 1e-3,
            "r 1 white metal albedo {rough} vs {want}"
        );
        // A smooth white metal keeps almost everything at normal incidence.
        let smooth = specular_albedo(1.0, 0.1, N);
        assert!(smooth > 0.99, "r 0.1 white metal albedo {smooth}");
        for (t, metal, dielectric) in loss_r1 {
            println!(
                "roughness 1, θo {t}°: energy loss metal {metal:.4}, dielectric {dielectric:.4}"
            );
        }
    }
}

/// How the camera view draws surfaces with MTL `d` < 1 (shadow and light maps always use
/// hashed coverage).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum Transparency {
    /// Per-pixel linked lists (Yang et al. 2010; Dachsbacher 2014): every layer shaded, sorted
    /// by depth per pixel and blended back to front over the lit opaque frame.
    #[default]
    Oit,
    /// Hashed alpha testing in the G-buffer (Wyman and McGuire 2017): a fragment survives with
    /// probability d, so the image is noisy but needs no sort.
    Hashed,
}

/// The words of [`Transparency`] in scene files and flags.
pub const TRANSPARENCY_NAMES: [(&str, Transparency); 2] =
    [("oit", Transparency::Oit), ("hashed", Transparency::Hashed)];
