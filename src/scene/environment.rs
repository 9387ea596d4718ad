//! The `[environment]` table: light arriving from infinitely far away, seen by camera rays
//! that miss every surface and by GI rays that leave the voxel grid.
//!
//! # Convention (Mitsuba 3's `envmap`)
//! World +Y is up. A map is equirectangular, `width = 2 × height`. For a direction `d` in the
//! map's own frame (the world direction rotated by `-rotation_deg` about +Y),
//! `u = atan2(d.x, -d.z) / 2π` (wrapped to [0, 1)) and `v = acos(d.y) / π`: the top row
//! (`v = 0`) is straight up, `u = 0` looks along −Z, `u = 1/4` along +X, `u = 1/2` along +Z
//! and `u = 3/4` along −X, as Mitsuba 3's `envmap` emitter maps `-si.wi` (its
//! `src/emitters/envmap.cpp`, `eval`). `rotation_deg` turns the map about +Y the way
//! Mitsuba's `<rotate y="1" angle="…"/>` on the emitter's `to_world` does (counter-clockwise
//! seen from above), so the export writes it unchanged.

use std::path::{Path, PathBuf};

use glam::Vec3;

/// A validated `kind = "sky"` table (evaluated and baked by `super::sky`).
#[derive(Clone, Debug, PartialEq)]
pub struct SkyParams {
    /// Atmospheric turbidity, 1..=10 (Mitsuba's `turbidity`).
    pub turbidity: f32,
    /// The ground's albedo per channel, 0..=1 (Mitsuba's `albedo`): the light the ground
    /// reflects back into the atmosphere, which brightens the sky near the horizon.
    pub ground_albedo: Vec3,
    /// Factor on the sky's radiance (Mitsuba's `sky_scale`).
    pub scale: f32,
    /// Unit direction toward the sun: the scene's first directional light, reversed.
    pub toward_sun: Vec3,
}

/// Where the light from far away comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The same radiance from every direction, W/(m²·sr) (Mitsuba's `constant` emitter).
    Constant { radiance: Vec3 },
    /// An equirectangular map (Mitsuba's `envmap` emitter).
    Map(EnvironmentMap),
    /// Hosek and Wilkie's analytic sky whose sun is the scene's directional light (Mitsuba's
    /// `sunsky` emitter without its sun disk), baked into `map` at load (`super::sky`).
    Sky { sky: SkyParams, map: EnvironmentMap },
}

/// A decoded equirectangular map (linear RGB radiance before `scale`).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    /// The file, as resolved against the scene's directory.
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// RGBA f32 texels, row 0 at the top (+Y), alpha 1.
    pub texels: Vec<f32>,
    /// Rotation about +Y in degrees (Mitsuba's `to_world` rotate).
    pub rotation_deg: f32,
    /// Factor on every texel (Mitsuba's `scale`).
    pub scale: f32,
}

/// The kinds the `kind` key takes.
pub const ENVIRONMENT_KINDS: [&str; 3] = ["constant", "map", "sky"];

impl Environment {
    /// The shaders' `ENVIRONMENT` specialization constant (`glsl/include/environment.glsl`):
    /// 0 none, 1 constant, 2 map (a sky is its baked map). Shaders compile the lookup in only
    /// where it is not 0, so a scene without the table carries no environment code.
    pub fn shader_kind(environment: Option<&Environment>) -> u32 {
        match environment {
            None => 0,
            Some(Environment::Constant { .. }) => 1,
            Some(Environment::Map(_) | Environment::Sky { .. }) => 2,
        }
    }

    /// The map the shaders sample: the file's, or the sky's bake; `None` for a constant.
    pub fn map(&self) -> Option<&EnvironmentMap> {
        match self {
            Environment::Constant { .. } => None,
            Environment::Map(m) | Environment::Sky { map: m, .. } => Some(m),
        }
    }

    /// `GpuFrame::environment`: rgb the constant's radiance or the map's scale, w the map's
    /// rotation about +Y in radians; zero without an environment.
    pub fn frame_constants(environment: Option<&Environment>) -> [f32; 4] {
        match environment {
            None => [0.0; 4],
            Some(Environment::Constant { radiance }) => radiance.extend(0.0).to_array(),
            Some(Environment::Map(m) | Environment::Sky { map: m, .. }) => {
                [m.scale, m.scale, m.scale, m.rotation_deg.to_radians()]
            }
        }
    }

    /// The radiance arriving from direction `toward` (unit, pointing away from the scene,
    /// i.e. the direction a ray travels), as the shaders' `environment_radiance` computes it
    /// with nearest-texel lookup. For tests and CPU references.
    pub fn radiance_toward(&self, toward: Vec3) -> Vec3 {
        match self {
            Environment::Constant { radiance } => *radiance,
            Environment::Map(m) | Environment::Sky { map: m, .. } => {
                let (u, v) = equirect_uv(toward, m.rotation_deg.to_radians());
                let x = ((u * m.width as f32) as u32).min(m.width - 1);
                let y = ((v * m.height as f32) as u32).min(m.height - 1);
                let i = 4 * (y as usize * m.width as usize + x as usize);
                Vec3::new(m.texels[i], m.texels[i + 1], m.texels[i + 2]) * m.scale
            }
        }
    }

    /// The mean radiance over the sphere of directions (solid-angle weighted): the constant,
    /// or the map's texels weighted by sin θ of their row. For tests.
    pub fn mean_radiance(&self) -> Vec3 {
        match self {
            Environment::Constant { radiance } => *radiance,
            Environment::Map(m) | Environment::Sky { map: m, .. } => {
                let mut sum = Vec3::ZERO;
                let mut weight = 0.0;
                for y in 0..m.height {
                    let theta = (y as f32 + 0.5) / m.height as f32 * std::f32::consts::PI;
                    let w = theta.sin();
                    for x in 0..m.width {
                        let i = 4 * (y as usize * m.width as usize + x as usize);
                        sum += Vec3::new(m.texels[i], m.texels[i + 1], m.texels[i + 2]) * w;
                        weight += w;
                    }
                }
                sum / weight.max(f32::MIN_POSITIVE) * m.scale
            }
        }
    }
}

/// The equirectangular coordinates of world direction `d` (unit) under a map rotated by
/// `rotation_rad` about +Y: the CPU twin of `environment_uv` in `glsl/include/environment.glsl`
/// (see the module documentation for the convention).
pub fn equirect_uv(d: Vec3, rotation_rad: f32) -> (f32, f32) {
    // World to map frame: the inverse of Mitsuba's rotate about +Y, R(θ)ᵀ.
    let (s, c) = rotation_rad.sin_cos();
    let local = Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    let u = local.x.atan2(-local.z) / std::f32::consts::TAU;
    let v = local.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
    (u - u.floor(), v)
}

/// The direction of a map's `(u, v)`, in world space: the inverse of [`equirect_uv`].
pub fn equirect_direction(u: f32, v: f32, rotation_rad: f32) -> Vec3 {
    let phi = u * std::f32::consts::TAU;
    let theta = v * std::f32::consts::PI;
    let local = Vec3::new(
        theta.sin() * phi.sin(),
        theta.cos(),
        -theta.sin() * phi.cos(),
    );
    let (s, c) = rotation_rad.sin_cos();
    Vec3::new(
        c * local.x + s * local.z,
        local.y,
        -s * local.x + c * local.z,
    )
}

/// The importance-sampling tables of an equirectangular map (`gi.env_sampling`), as
/// `glsl/include/environment_sampling.glsl` reads them; `tools/envis_twin.py` is the numpy
/// oracle this follows step by step.
///
/// Each texel's weight is its luminance smoothed by [1/8, 3/4, 1/8] in u (repeating) and in v
/// (clamped), the integral of the bilinear lookup's hat over the texel in each axis, so every
/// texel the lookup spreads a bright texel into has weight, times sin θ at the row's centre
/// (a texel's solid angle is 2π² sin θ du dv). `values` holds the marginal CDF over rows
/// (`height + 1` values, 0 first and 1 last), then each row's conditional CDF over its columns
/// (`width + 1` values each; a black row's is uniform and never picked, its marginal interval
/// being empty). A texel's probability is the product of its two intervals, exact in f32
/// (the difference of two nearby floats is exact, Sterbenz's lemma), so the shader's density is
/// the one its binary search samples.
///
/// `map_share` is α, the share of the environment's samples the renderers draw from these
/// tables (the rest from the BSDF), chosen from how concentrated the map's power is: see
/// [`map_share`].
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentCdf {
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
    pub map_share: f32,
}

/// The solid angle, as a fraction of the sphere, whose power decides α ([`map_share`]).
pub const MAP_SHARE_SOLID_ANGLE: f64 = 0.01;

/// The share of the power in the brightest [`MAP_SHARE_SOLID_ANGLE`] from which a map is
/// sampled: a majority.
pub const MAP_SHARE_GATE: f64 = 0.5;

/// The largest α: the BSDF keeps at least half of the samples, so a one-sample mixture's
/// second moment is at most 1/(1 − α) = 2 times the BSDF's alone wherever the map's density
/// misleads (cos θ and occlusion, which the map does not know).
pub const MAP_SHARE_MAX: f64 = 0.5;

/// α, the share of samples drawn from the map, from the texels' power (`weights`, luminance
/// times sin θ, so a texel's solid angle is proportional to sin θ): s, the share of the power
/// in the brightest fraction a = [`MAP_SHARE_SOLID_ANGLE`] of the sphere (texels ordered by
/// luminance, the last one counted in part); α = [`MAP_SHARE_MAX`] where s reaches
/// [`MAP_SHARE_GATE`], else 0.
///
/// Why: take a map of two levels, a part of solid angle a holding s of the power and the rest
/// uniform, sampled by the mixture q = α p_map + (1 − α) p_bsdf where the map's samples land
/// on the bright part and the BSDF's spread evenly (in its own measure), all independent. The
/// estimator's relative second moment is s²/(a + α(1 − a)) + (1 − s)²/((1 − a)(1 − α)); its
/// derivative in α vanishes at s(1 − a)(1 − α) = (1 − s)(a + α(1 − a)), i.e.
/// α* = (s − a)/(1 − a) (Veach 1997, §9.2.2 for the mixture), which exceeds the cap as soon
/// as s > 0.505: a sun holding most of the power. Below that the model flatters the map: the
/// BSDF's samples are stratified, which removes most of the error of a smooth sky (a glow a
/// stratum wide) but not of a source smaller than a stratum, and the map does not know which
/// of its bright directions a surface's walls hide. Measured on the smooth skies
/// (docs/measurements/environment.md: s = 0.075 and about 0.05, α* = 0.066 and 0.04), even
/// one map sample in 16 made the direct light 7% and 16% worse, so those maps keep the BSDF's
/// samples alone (α = 0, exactly the render without importance sampling).
fn map_share(weights: &[f64], w: usize, h: usize) -> f64 {
    let total: f64 = weights.iter().sum();
    let sphere: f64 = (0..h)
        .map(|y| w as f64 * (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin())
        .sum();
    if total <= 0.0 || sphere <= 0.0 {
        return 0.0;
    }
    // (luminance, power, solid angle as a fraction of the sphere) per texel, brightest first.
    let mut texels: Vec<(f64, f64, f64)> = weights
        .iter()
        .enumerate()
        .filter_map(|(i, &p)| {
            let sin = (std::f64::consts::PI * ((i / w) as f64 + 0.5) / h as f64).sin();
            (sin > 0.0).then(|| (p / sin, p / total, sin / sphere))
        })
        .collect();
    texels.sort_by(|a, b| b.0.total_cmp(&a.0));
    let (mut s, mut covered) = (0.0, 0.0);
    for &(_, power, omega) in &texels {
        let take = ((MAP_SHARE_SOLID_ANGLE - covered) / omega).min(1.0);
        if take <= 0.0 {
            break;
        }
        s += power * take;
        covered += omega * take;
    }
    if s >= MAP_SHARE_GATE {
        MAP_SHARE_MAX
    } else {
        0.0
    }
}

impl EnvironmentCdf {
    /// The tables of `map`; `None` for a black map (nothing to sample).
    pub fn new(map: &EnvironmentMap) -> Option<Self> {
        let (w, h) = (map.width as usize, map.height as usize);
        if w == 0 || h == 0 {
            return None;
        }
        let lum: Vec<f64> = map
            .texels
            .chunks_exact(4)
            .map(|t| 0.2126 * f64::from(t[0]) + 0.7152 * f64::from(t[1]) + 0.0722 * f64::from(t[2]))
            .map(|y| y.max(0.0))
            .collect();
        let at = |x: usize, y: usize| lum[y * w + x];
        let mut weights = vec![0.0f64; w * h];
        for y in 0..h {
            let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
            let theta = std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
            for x in 0..w {
                let (left, right) = ((x + w - 1) % w, (x + 1) % w);
                let row = |r: usize| 0.75 * at(x, r) + 0.125 * (at(left, r) + at(right, r));
                weights[y * w + x] = (0.75 * row(y) + 0.125 * (row(up) + row(down))) * theta.sin();
            }
        }
        let rows: Vec<f64> = weights.chunks_exact(w).map(|r| r.iter().sum()).collect();
        let total: f64 = rows.iter().sum();
        if total <= 0.0 || !total.is_finite() {
            return None;
        }
        let map_share = map_share(&weights, w, h) as f32;
        let mut values = Vec::with_capacity(h + 1 + h * (w + 1));
        values.extend(cumulative(&rows, total));
        for (r, &sum) in weights.chunks_exact(w).zip(&rows) {
            if sum > 0.0 {
                values.extend(cumulative(r, sum));
            } else {
                values.extend((0..=w).map(|i| (i as f64 / w as f64) as f32));
            }
        }
        Some(Self {
            width: map.width,
            height: map.height,
            values,
            map_share,
        })
    }

    /// The probability of picking texel (x, y): its marginal interval times its conditional's.
    pub fn texel_probability(&self, x: u32, y: u32) -> f64 {
        let (w, h) = (self.width as usize, self.height as usize);
        let (x, y) = (x as usize, y as usize);
        let m = &self.values[..=h];
        let c = &self.values[h + 1 + y * (w + 1)..][..=w];
        f64::from(m[y + 1] - m[y]) * f64::from(c[x + 1] - c[x])
    }

    /// The buffer the shaders read: a `uvec4` header (width, height, the bits of
    /// `map_share`, 0), then `values`.
    pub fn to_gpu_bytes(&self) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(16 + 4 * self.values.len());
        for v in [self.width, self.height, self.map_share.to_bits(), 0] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for v in &self.values {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes
    }
}

/// `weights`' running sums divided by `total`, with 0 before them and the last set to exactly 1.
fn cumulative(weights: &[f64], total: f64) -> Vec<f32> {
    let mut out = Vec::with_capacity(weights.len() + 1);
    out.push(0.0);
    let mut acc = 0.0;
    for w in weights {
        acc += w;
        out.push((acc / total).min(1.0) as f32);
    }
    if let Some(last) = out.last_mut() {
        *last = 1.0;
    }
    out
}

/// Why a map could not be read (the caller turns it into a [`super::SceneError`] naming the
/// scene file and the key).
#[derive(Debug)]
pub(crate) enum MapReadError {
    NotFound,
    Decode(String),
    NotTwoToOne { width: u32, height: u32 },
    NonFinite { x: u32, y: u32 },
}

/// Reads an equirectangular map (Radiance `.hdr`, OpenEXR, or anything else the `image`
/// crate decodes; 8-bit formats are taken as sRGB-encoded and linearized by the decoder's
/// conversion to f32, which is linear for HDR formats only, so LDR files are refused).
pub(crate) fn read_map(path: &Path) -> Result<(u32, u32, Vec<f32>), MapReadError> {
    if !path.is_file() {
        return Err(MapReadError::NotFound);
    }
    let reader = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| MapReadError::Decode(e.to_string()))?;
    let format = reader.format();
    if !matches!(
        format,
        Some(image::ImageFormat::Hdr) | Some(image::ImageFormat::OpenExr)
    ) {
        return Err(MapReadError::Decode(
            "not a Radiance .hdr or OpenEXR file (an environment map holds linear radiance)".into(),
        ));
    }
    let img = reader
        .decode()
        .map_err(|e| MapReadError::Decode(e.to_string()))?
        .into_rgba32f();
    let (width, height) = img.dimensions();
    if width != 2 * height || height == 0 {
        return Err(MapReadError::NotTwoToOne { width, height });
    }
    let mut texels = img.into_raw();
    for (i, t) in texels.chunks_exact_mut(4).enumerate() {
        if !t[..3].iter().all(|c| c.is_finite()) {
            let i = i as u32;
            return Err(MapReadError::NonFinite {
                x: i % width,
                y: i / width,
            });
        }
        // Negative values (some EXR writers' ringing) are not radiance.
        for c in &mut t[..3] {
            *c = c.max(0.0);
        }
        t[3] = 1.0;
    }
    Ok((width, height, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equirect_matches_mitsubas_axes() {
        // Mitsuba 3 envmap: u = atan2(x, -z) / 2π, v = acos(y) / π.
        let close = |a: (f32, f32), b: (f32, f32)| {
            let du = (a.0 - b.0).abs().min(1.0 - (a.0 - b.0).abs());
            du < 1e-5 && (a.1 - b.1).abs() < 1e-5
        };
        assert!(close(equirect_uv(Vec3::NEG_Z, 0.0), (0.0, 0.5)));
        assert!(close(equirect_uv(Vec3::X, 0.0), (0.25, 0.5)));
        assert!(close(equirect_uv(Vec3::Z, 0.0), (0.5, 0.5)));
        assert!(close(equirect_uv(Vec3::NEG_X, 0.0), (0.75, 0.5)));
        assert!((equirect_uv(Vec3::Y, 0.0).1).abs() < 1e-6);
        assert!((equirect_uv(Vec3::NEG_Y, 0.0).1 - 1.0).abs() < 1e-6);
        // Rotating the map by +90° about +Y (counter-clockwise from above) carries the map's −Z
        // column to world −X: R_y(90°) (0, 0, −1) = (−1, 0, 0).
        assert!(close(
            equirect_uv(Vec3::NEG_X, 90f32.to_radians()),
            (0.0, 0.5)
        ));
    }

    fn scene_with(environment: &str, dir: &Path) -> Result<super::super::Scene, String> {
        let toml = format!(
            "[camera]\nposition = [0, 1, -2]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n[[objects]]\nbuiltin = \"quad\"\n\
             [environment]\n{environment}\n"
        );
        super::super::Scene::from_toml_str(&toml, Path::new("sky.toml"), dir)
            .map_err(|e| e.to_string())
    }

    fn temp_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("voxgi-env-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn write_exr(path: &Path, w: u32, h: u32, value: f32) {
        image::Rgb32FImage::from_raw(w, h, vec![value; (w * h * 3) as usize])
            .unwrap()
            .save_with_format(path, image::ImageFormat::OpenExr)
            .unwrap();
    }

    #[test]
    fn tables_parse_into_constant_and_map() {
        let dir = temp_dir("ok");
        write_exr(&dir.join("sky.exr"), 8, 4, 0.5);
        let s = scene_with("kind = \"constant\"\nradiance = [1, 2, 3]", &dir).unwrap();
        assert_eq!(
            s.environment,
            Some(Environment::Constant {
                radiance: Vec3::new(1.0, 2.0, 3.0)
            })
        );
        let s = scene_with(
            "kind = \"map\"\nfile = \"sky.exr\"\nrotation_deg = 45\nscale = 2",
            &dir,
        )
        .unwrap();
        let Some(Environment::Map(m)) = &s.environment else {
            panic!("not a map: {:?}", s.environment)
        };
        assert_eq!(
            (m.width, m.height, m.rotation_deg, m.scale),
            (8, 4, 45.0, 2.0)
        );
        assert_eq!(m.texels.len(), 8 * 4 * 4);
        assert!(
            (s.environment.as_ref().unwrap().mean_radiance() - Vec3::splat(1.0))
                .abs()
                .max_element()
                < 1e-6
        );
        assert!(scene_with("", &dir).is_err(), "kind is required");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_tables_name_the_file_and_key() {
        let dir = temp_dir("bad");
        write_exr(&dir.join("square.exr"), 4, 4, 1.0);
        std::fs::write(dir.join("sky.png"), b"not really").unwrap();
        let cases = [
            (
                "kind = \"sphere\"",
                vec!["sky.toml", "environment.kind", "\"constant\", \"map\""],
            ),
            (
                "kind = \"constant\"",
                vec!["sky.toml", "environment.radiance", "missing"],
            ),
            (
                "kind = \"constant\"\nradiance = [1, -1, 1]",
                vec!["sky.toml", "environment.radiance"],
            ),
            (
                "kind = \"constant\"\nradiance = 1\nscale = 2",
                vec!["environment.scale", "does not apply"],
            ),
            (
                "kind = \"map\"",
                vec!["sky.toml", "environment.file", "missing"],
            ),
            (
                "kind = \"map\"\nfile = \"nowhere.hdr\"",
                vec![
                    "nowhere.hdr",
                    "environment map not found",
                    "sky.toml: environment.file",
                ],
            ),
            (
                "kind = \"map\"\nfile = \"square.exr\"",
                vec!["sky.toml", "environment.file", "4×4", "twice as wide"],
            ),
            (
                "kind = \"map\"\nfile = \"sky.png\"",
                vec!["sky.png", "sky.toml: environment.file"],
            ),
            (
                "kind = \"map\"\nfile = \"square.exr\"\nscale = -1",
                vec!["environment.scale", "negative"],
            ),
            (
                "kind = \"sky\"",
                vec![
                    "sky.toml",
                    "environment.kind",
                    "directional light",
                    "[[lights]]",
                ],
            ),
            (
                "kind = \"map\"\nfile = \"square.exr\"\nturbidity = 3",
                vec!["environment.turbidity", "does not apply"],
            ),
            ("kind = \"map\"\ncolour = 1", vec!["colour"]),
        ];
        for (table, words) in cases {
            let err = scene_with(table, &dir).expect_err(table);
            for w in words {
                assert!(err.contains(w), "{table:?}: {err:?} lacks {w:?}");
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A sky takes its sun from the first directional light and checks its own keys.
    #[test]
    fn sky_tables_take_the_directional_light_as_their_sun() {
        let dir = temp_dir("sky");
        let sun = "[[lights]]\nkind = \"point\"\nposition = [0, 3, 0]\nintensity_w_sr = 1\n\
                   [[lights]]\nkind = \"directional\"\ndirection = [0, -1, 1]\n\
                   irradiance_w_m2 = 2\n";
        let sky_scene = |table: &str| {
            let toml = format!(
                "[camera]\nposition = [0, 1, -2]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
                 [[objects]]\nbuiltin = \"quad\"\n{sun}[environment]\nkind = \"sky\"\n{table}\n"
            );
            super::super::Scene::from_toml_str(&toml, Path::new("sky.toml"), &dir)
                .map_err(|e| e.to_string())
        };
        let s = sky_scene("turbidity = 4.5\nground_albedo = [0.1, 0.2, 0.3]\nscale = 2").unwrap();
        let Some(Environment::Sky { sky, map }) = &s.environment else {
            panic!("not a sky: {:?}", s.environment)
        };
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert!((sky.toward_sun - Vec3::new(0.0, h, -h)).length() < 1e-6);
        assert_eq!(
            (sky.turbidity, sky.ground_albedo, sky.scale),
            (4.5, Vec3::new(0.1, 0.2, 0.3), 2.0)
        );
        assert_eq!(
            (map.width, map.height),
            (
                super::super::sky::BAKE_WIDTH,
                super::super::sky::BAKE_HEIGHT
            )
        );
        assert_eq!(Environment::shader_kind(s.environment.as_ref()), 2);
        // Defaults: Mitsuba's (turbidity 3, albedo 0.3, scale 1).
        let s = sky_scene("").unwrap();
        let Some(Environment::Sky { sky, .. }) = &s.environment else {
            panic!("not a sky")
        };
        assert_eq!(
            (sky.turbidity, sky.ground_albedo, sky.scale),
            (3.0, Vec3::splat(0.3), 1.0)
        );
        for (table, words) in [
            ("turbidity = 0.5", vec!["environment.turbidity", "1..=10"]),
            ("turbidity = 11", vec!["environment.turbidity"]),
            ("ground_albedo = 1.5", vec!["environment.ground_albedo"]),
            ("scale = -2", vec!["environment.scale", "negative"]),
            (
                "file = \"sky.exr\"",
                vec!["environment.file", "does not apply"],
            ),
            (
                "radiance = 1",
                vec!["environment.radiance", "does not apply"],
            ),
        ] {
            let err = sky_scene(table).expect_err(table);
            for w in words {
                assert!(err.contains(w), "{table:?}: {err:?} lacks {w:?}");
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn direction_inverts_uv() {
        for &(u, v, r) in &[(0.1, 0.3, 0.0), (0.7, 0.8, 1.0), (0.45, 0.05, -2.5)] {
            let d = equirect_direction(u, v, r);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let (u2, v2) = equirect_uv(d, r);
            assert!(
                (u - u2).abs() < 1e-4 && (v - v2).abs() < 1e-4,
                "{u} {v} {u2} {v2}"
            );
        }
    }

    fn map_of(w: u32, h: u32, texel: impl Fn(u32, u32) -> f32) -> EnvironmentMap {
        let mut texels = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = texel(x, y);
                texels.extend_from_slice(&[v, v, v, 1.0]);
            }
        }
        EnvironmentMap {
            path: PathBuf::from("test.exr"),
            width: w,
            height: h,
            texels,
            rotation_deg: 0.0,
            scale: 1.0,
        }
    }

    /// A constant map's texels are picked by their solid angle alone: sin θ of the row over
    /// W Σ_rows sin θ (the smoothing keeps a constant constant).
    #[test]
    fn cdf_of_a_constant_map_follows_the_solid_angle() {
        let (w, h) = (16, 8);
        let Some(cdf) = EnvironmentCdf::new(&map_of(w, h, |_, _| 2.0)) else {
            panic!("a constant map has tables");
        };
        assert_eq!(cdf.values.len(), (h + 1 + h * (w + 1)) as usize);
        let sin = |y: u32| (std::f64::consts::PI * (f64::from(y) + 0.5) / f64::from(h)).sin();
        let sum: f64 = (0..h).map(sin).sum();
        for y in 0..h {
            for x in 0..w {
                let want = sin(y) / (f64::from(w) * sum);
                let got = cdf.texel_probability(x, y);
                assert!(
                    (got - want).abs() < 1e-6 * want.max(1e-3),
                    "{x} {y}: {got} {want}"
                );
            }
        }
    }

    /// A 2 x 2-texel sun: the probabilities sum to 1, the sun's texels hold nearly all of it,
    /// and every texel the bilinear lookup spreads the sun into (its 4 x 4 neighbourhood) can be
    /// picked, while texels farther away cannot (their radiance is 0, so no bias).
    #[test]
    fn cdf_of_a_sun_covers_the_bilinear_footprint() {
        let (w, h) = (32, 16);
        let sun = |x: u32, y: u32| (10..12).contains(&x) && (5..7).contains(&y);
        let Some(cdf) =
            EnvironmentCdf::new(&map_of(w, h, |x, y| if sun(x, y) { 100.0 } else { 0.0 }))
        else {
            panic!("a sun map has tables");
        };
        let mut total = 0.0;
        let mut in_sun = 0.0;
        for y in 0..h {
            for x in 0..w {
                let p = cdf.texel_probability(x, y);
                total += p;
                if sun(x, y) {
                    in_sun += p;
                }
                let near = (9..13).contains(&x) && (4..8).contains(&y);
                assert_eq!(p > 0.0, near, "texel {x} {y}: {p}");
            }
        }
        assert!((total - 1.0).abs() < 1e-6, "{total}");
        // The smoothing keeps (3/4 + 1/8)^2 = 0.77 of each sun texel's weight on the sun.
        assert!(in_sun > 0.7 && in_sun < 0.8, "{in_sun}");
        assert!(EnvironmentCdf::new(&map_of(w, h, |_, _| 0.0)).is_none());
    }

    /// α against its closed form: a constant map holds exactly a of the power in any a of the
    /// sphere, so α = 0. A map of two levels, L1 on 8 texels covering a fraction b < a of the
    /// sphere and L0 elsewhere, holds s = (b L1 + (a − b) L0)/(b L1 + (1 − b) L0) in its
    /// brightest a; L1 is chosen to put s 1% above and below the gate, which decides α.
    #[test]
    fn map_share_follows_the_power_in_the_brightest_solid_angle() {
        let (w, h) = (64usize, 32usize);
        let sin = |y: usize| (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
        let weights = |lum: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
            (0..w * h).map(|i| lum(i % w, i / w) * sin(i / w)).collect()
        };
        let constant = map_share(&weights(&|_, _| 2.0), w, h);
        assert_eq!(constant, 0.0);
        // Texels 20-23 of rows 14 and 15 (next to the equator).
        let spot = |x: usize, y: usize| (20..24).contains(&x) && (y == 14 || y == 15);
        let sphere: f64 = (0..h).map(|y| w as f64 * sin(y)).sum();
        let b = 4.0 * (sin(14) + sin(15)) / sphere;
        let a = MAP_SHARE_SOLID_ANGLE;
        assert!(b < a, "the spot is smaller than a: {b}");
        let l0 = 1.0;
        // s(L1) = (b L1 + (a − b) L0)/(b L1 + (1 − b) L0) = t solved for L1.
        let l1_for = |t: f64| (t * (1.0 - b) * l0 - (a - b) * l0) / (b * (1.0 - t));
        for (t, expected) in [
            (1.01 * MAP_SHARE_GATE, MAP_SHARE_MAX),
            (0.99 * MAP_SHARE_GATE, 0.0),
        ] {
            let l1 = l1_for(t);
            let got = map_share(&weights(&|x, y| if spot(x, y) { l1 } else { l0 }), w, h);
            assert_eq!(got, expected, "s = {t}, L1 = {l1}");
        }
    }
}
