//! The MTL texture maps in the voxel volumes (docs/design/materials.md): `map_Kd` in
//! the albedo volume, `map_Ke` in the emission volume, `map_Pr` / `map_Pm` in the material
//! volume, sampled per texel at the surface points each voxelizer averages, instead of `Kd`
//! or each map's mean; and `map_Ke` at the points the VPL emitter rays start from.
//!
//! The maps a scene's volumes read go into one storage buffer of linear half-float texels
//! (sRGB decoded on the CPU; every map's mip chain, [`TextureData::mip_chain`], the G-buffer's
//! levels) with a table row per scene texture ([`VoxelMaps`]), so one dispatch or one draw
//! samples the maps of every material
//! (`glsl/include/voxel_maps.glsl`; no descriptor per texture). Each triangle carries its
//! texture coordinates, its maps and the level of detail of the voxelizer's sample spacing
//! ([`GpuTriangleMaps`]). Scenes without such maps, methods that read no volume the maps feed,
//! and `GiSettings::voxel_map_texels = false` (the per-material means, for comparisons) get
//! none of it: no buffer, no binding read, no sampling (a specialization constant).

use crate::graph::{Access, BufferHandle, RenderGraph};
use crate::scene::{Material, Scene, TextureData};
use crate::vk::{vk, Buffer, Context, VkError};
use glam::{Vec2, Vec3};

/// Which volumes sample their maps per texel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MapUse {
    /// The emission volume samples `map_Ke`.
    pub emission: bool,
    /// The material volume samples `map_Pr` and `map_Pm` (GGX materials).
    pub lobe: bool,
    /// The albedo volume samples `map_Kd` (sRGB, decoded before averaging, as the
    /// G-buffer's sampler decodes it).
    pub albedo: bool,
}

impl MapUse {
    /// The maps a scene's volumes sample: `emission` / `material` say which volumes exist
    /// (the albedo volume always does), `per_texel` whether maps are sampled at all (else each
    /// map's mean and `Kd`). A volume whose materials have no map samples none.
    pub fn new(scene: &Scene, emission: bool, material: bool, per_texel: bool) -> Self {
        let has = |f: &dyn Fn(&Material) -> bool| scene.materials.iter().any(f);
        Self {
            emission: per_texel && emission && has(&|m| m.pbr_maps.emission.is_some()),
            lobe: per_texel
                && material
                && has(&|m| {
                    m.ggx.is_some()
                        && (m.pbr_maps.roughness.is_some() || m.pbr_maps.metallic.is_some())
                }),
            albedo: per_texel && has(&|m| m.albedo_texture.is_some()),
        }
    }

    /// Only the albedo volume's `map_Kd` (the albedo debug view, which has no value volumes),
    /// where `scene` has albedo textures.
    pub fn albedo_only(scene: &Scene) -> Self {
        Self {
            albedo: scene.materials.iter().any(|m| m.albedo_texture.is_some()),
            ..Self::default()
        }
    }

    /// Some volume samples a map.
    pub fn any(self) -> bool {
        self.emission || self.lobe || self.albedo
    }

    /// The maps of `m` that these volumes sample: (roughness, metallic, emission, albedo)
    /// texture indices, -1 where none.
    pub fn maps_of(self, m: &Material) -> [i32; 4] {
        let index = |on: bool, t: Option<usize>| match t {
            Some(t) if on => i32::try_from(t).unwrap_or(-1),
            _ => -1,
        };
        let lobe = self.lobe && m.ggx.is_some();
        [
            index(lobe, m.pbr_maps.roughness),
            index(lobe, m.pbr_maps.metallic),
            index(self.emission, m.pbr_maps.emission),
            index(self.albedo, m.albedo_texture),
        ]
    }
}

/// A triangle's maps as `voxel_maps.glsl` reads them (see there): texture coordinates, the
/// log2 of the voxelizer's sample spacing in texture-coordinate units, and the maps.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTriangleMaps {
    pub uv01: [f32; 4],
    /// uv2, the lod, 0.
    pub uv2_lod: [f32; 4],
    /// Roughness, metallic, emission and albedo texture indices (-1: none).
    pub maps: [i32; 4],
}

impl GpuTriangleMaps {
    /// The row of a triangle at `p` (meters) with texture coordinates `uv` (zero without; the
    /// G-buffer's vertices have zero then too) whose maps are `maps` ([`MapUse::maps_of`]),
    /// sampled every `spacing_m` meters: the level of detail makes one texel of the level read
    /// about one spacing wide, so the samples together cover every texel (a box filter, the
    /// albedo volume's area-weighted mean, not aliasing).
    pub fn new(maps: [i32; 4], p: [Vec3; 3], uv: [Vec2; 3], spacing_m: f32) -> Self {
        let world_area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        let uv_area = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
        // Texture-coordinate units per meter along the surface (isotropic estimate).
        let lod = (0.5 * (uv_area / world_area).log2() + spacing_m.log2()).clamp(-64.0, 64.0);
        let lod = if lod.is_nan() { -64.0 } else { lod };
        Self {
            uv01: [uv[0].x, uv[0].y, uv[1].x, uv[1].y],
            uv2_lod: [uv[2].x, uv[2].y, lod, 0.0],
            maps,
        }
    }

    /// The row of a triangle that reads no map.
    pub const NONE: Self = Self {
        uv01: [0.0; 4],
        uv2_lod: [0.0; 4],
        maps: [-1; 4],
    };

    /// The row as three `vec4`s (the layouts that interleave it with values).
    pub fn to_vec4s(self) -> [[f32; 4]; 3] {
        [
            self.uv01,
            self.uv2_lod,
            self.maps.map(|i| f32::from_bits(i as u32)),
        ]
    }
}

/// The texels and table of the maps a scene's volumes sample (see the module doc).
pub struct VoxelMaps {
    texels: Buffer,
    table: Buffer,
}

impl VoxelMaps {
    /// The maps `used` samples in `scene`, or `None` when it samples none.
    pub fn new(ctx: &Context, scene: &Scene, used: MapUse) -> Result<Option<Self>, VkError> {
        if !used.any() {
            return Ok(None);
        }
        let (texels, table) = map_texels(scene, used);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let texels = ctx.upload_buffer("voxel map texels", bytemuck::cast_slice(&texels), usage)?;
        let table = ctx.upload_buffer("voxel map table", bytemuck::cast_slice(&table), usage)?;
        Ok(Some(Self { texels, table }))
    }

    /// Imports `(texels, table)` into `g` with `access` (a shader read).
    pub fn import(&self, g: &mut RenderGraph, access: Access) -> (BufferHandle, BufferHandle) {
        (
            g.import_buffer(&self.texels, access),
            g.import_buffer(&self.table, access),
        )
    }
}

/// The texels of every level of every map `used` samples, each as linear RGBA in two
/// `packHalf2x16` words (sRGB decoded here, so a lookup needs no `pow`), and a table row per
/// scene texture: first texel, width, height, levels (zero for textures no volume samples).
/// Never empty.
pub fn map_texels(scene: &Scene, used: MapUse) -> (Vec<u32>, Vec<[u32; 4]>) {
    let mut sampled = vec![false; scene.textures.len()];
    for m in &scene.materials {
        for t in used.maps_of(m) {
            if let Some(s) = usize::try_from(t).ok().and_then(|t| sampled.get_mut(t)) {
                *s = true;
            }
        }
    }
    let mut texels: Vec<u32> = Vec::new();
    let mut table = vec![[0u32; 4]; scene.textures.len().max(1)];
    for ((t, row), _) in scene
        .textures
        .iter()
        .zip(table.iter_mut())
        .zip(&sampled)
        .filter(|(_, &s)| s)
    {
        let levels = t.mip_chain();
        *row = [
            (texels.len() / 2) as u32,
            t.width.max(1),
            t.height.max(1),
            levels.len() as u32,
        ];
        for level in &levels {
            for c in level.chunks_exact(4) {
                let v = linear_texel(c, t.srgb);
                texels.push(pack_half2(v[0], v[1]));
                texels.push(pack_half2(v[2], v[3]));
            }
        }
    }
    if texels.is_empty() {
        texels.extend([0, 0]);
    }
    (texels, table)
}

/// An RGBA8 texel as linear values (sRGB color channels decoded; alpha linear).
fn linear_texel(c: &[u8], srgb: bool) -> [f32; 4] {
    let mut v = [0, 1, 2, 3].map(|k| f32::from(c[k]) / 255.0);
    if srgb {
        for x in &mut v[..3] {
            *x = crate::eval::srgb_decode(*x);
        }
    }
    v
}

/// GLSL's `packHalf2x16`: `a` in the low 16 bits (round to nearest even; values here are in
/// [0, 1], so no overflow or subnormal handling beyond flushing below 2⁻¹⁴ to zero).
fn pack_half2(a: f32, b: f32) -> u32 {
    u32::from(f32_to_f16(a)) | (u32::from(f32_to_f16(b)) << 16)
}

/// An f32 in [0, 1] as an IEEE half: exponent rebiased, mantissa rounded to nearest even;
/// below the smallest normal half (6.1e-5, under a quarter of an 8-bit step) it is zero.
fn f32_to_f16(x: f32) -> u16 {
    let bits = x.max(0.0).to_bits();
    let exp = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    if exp <= 0 {
        return 0;
    }
    let mant = bits & 0x7f_ffff;
    let mut h = ((exp as u32) << 10) | (mant >> 13);
    let rest = mant & 0x1fff;
    if rest > 0x1000 || (rest == 0x1000 && h & 1 == 1) {
        h += 1;
    }
    h as u16
}

/// The sample spacing of the triangle voxelizer's value passes (`voxelize_owner_value.glsl`):
/// 4 × 4 samples across a voxel of `voxel_m` (its largest side).
pub fn owner_sample_spacing_m(voxel_m: Vec3) -> f32 {
    voxel_m.max_element() / 4.0
}

/// The CPU twin of `sample_voxel_map` (bilinear in the nearest level, wrapped), for tests and
/// references: the linear value of texture `t` at `uv` (v up) over a footprint of 2^`lod`
/// texture-coordinate units × texels.
pub fn sample_map_cpu(t: &TextureData, uv: Vec2, lod_uv: f32) -> glam::Vec4 {
    let (mut w, mut h) = (t.width.max(1) as i64, t.height.max(1) as i64);
    let l = lod_uv + 0.5 * ((w * h) as f32).log2();
    let mut level = (l + 0.5).floor().max(0.0) as usize;
    // Level 0 is the texture itself: no chain to build for the common case.
    let chain = if level > 0 { t.mip_chain() } else { Vec::new() };
    level = level.min(chain.len().saturating_sub(1));
    for _ in 0..level {
        w = (w / 2).max(1);
        h = (h / 2).max(1);
    }
    let data = chain.get(level).unwrap_or(&t.rgba8);
    let texel = |x: i64, y: i64| {
        let (x, y) = (x.rem_euclid(w), y.rem_euclid(h));
        let i = ((y * w + x) * 4) as usize;
        let c = glam::Vec4::from_array([0, 1, 2, 3].map(|k| f32::from(data[i + k]) / 255.0));
        if t.srgb {
            let d = crate::eval::srgb_decode;
            glam::Vec4::new(d(c.x), d(c.y), d(c.z), c.w)
        } else {
            c
        }
    };
    let st = Vec2::new(uv.x * w as f32 - 0.5, (1.0 - uv.y) * h as f32 - 0.5);
    let (x0, y0) = (st.x.floor() as i64, st.y.floor() as i64);
    let f = st - st.floor();
    // a + (b - a) f: the form the voxel volumes were measured with (glam's `lerp` rounds
    // a (1 - f) + b f differently).
    let a = texel(x0, y0).lerp_monotonic(texel(x0 + 1, y0), f.x);
    let b = texel(x0, y0 + 1).lerp_monotonic(texel(x0 + 1, y0 + 1), f.x);
    a.lerp_monotonic(b, f.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(w: u32, h: u32, srgb: bool, f: impl Fn(u32, u32) -> [u8; 3]) -> TextureData {
        let rgba8 = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .flat_map(|(x, y)| {
                let c = f(x, y);
                [c[0], c[1], c[2], 255]
            })
            .collect();
        TextureData::new("t".into(), w, h, rgba8, srgb)
    }

    #[test]
    fn triangle_lod_is_the_spacing_in_texture_units() {
        // A right triangle of legs 2 m mapped to legs 0.5 in uv: 0.25 uv units per meter, so
        // a spacing of 0.01 m is 0.0025 uv units: log2(0.0025).
        let p = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ];
        let uv = [Vec2::ZERO, Vec2::new(0.5, 0.0), Vec2::new(0.0, 0.5)];
        let row = GpuTriangleMaps::new([1, -1, 2, 3], p, uv, 0.01);
        assert!((row.uv2_lod[2] - 0.0025f32.log2()).abs() < 1e-5);
        assert_eq!(row.maps, [1, -1, 2, 3]);
        // Degenerate texture coordinates read level 0, never NaN.
        let flat = GpuTriangleMaps::new([0, -1, -1, -1], p, [Vec2::ZERO; 3], 0.01);
        assert_eq!(flat.uv2_lod[2], -64.0);
        let bits = row.to_vec4s()[2].map(f32::to_bits);
        assert_eq!(bits, [1, u32::MAX, 2, 3]);
        // Three vec4s, as voxel_maps.glsl reads a row.
        assert_eq!(std::mem::size_of::<GpuTriangleMaps>(), 48);
    }

    #[test]
    fn table_rows_point_at_each_maps_levels() {
        let mut scene = crate::scene::load_scene_arg(None).expect("cornell");
        scene.textures = vec![
            texture(4, 2, false, |x, _| [x as u8 * 60; 3]),
            texture(2, 2, true, |_, _| [9; 3]),
            texture(8, 8, false, |_, _| [1; 3]),
        ];
        let m = &mut scene.materials[0];
        m.ggx = Some(crate::scene::Ggx {
            roughness: 0.5,
            metallic: 0.0,
        });
        m.pbr_maps.roughness = Some(0);
        m.pbr_maps.emission = Some(1);
        m.emission = Vec3::ONE;
        let used = MapUse::new(&scene, true, true, true);
        assert_eq!(
            used,
            MapUse {
                emission: true,
                lobe: true,
                albedo: false,
            }
        );
        let (texels, table) = map_texels(&scene, used);
        // 4×2 → 2×1 → 1×1 (11 texels), then 2×2 → 1×1 (5), two words each; texture 2 is
        // sampled by no volume.
        assert_eq!(table[0], [0, 4, 2, 3]);
        assert_eq!(table[1], [11, 2, 2, 2]);
        assert_eq!(table[2], [0; 4]);
        assert_eq!(texels.len(), 32);
        // Texel 1 of the linear map: 60/255 = 0.2353 → half 0x3388 (0.23535), alpha 1 = 0x3c00.
        assert_eq!(texels[2], 0x3388 | 0x3388 << 16);
        assert_eq!(texels[3], 0x3388 | 0x3c00 << 16);
        // The sRGB map's code 9 is decoded first: 9/255/12.92 = 0.002732 → half 0x1998.
        assert_eq!(texels[22] & 0xffff, 0x1998);
        // Only the emission volume: the roughness map is not uploaded.
        let used = MapUse::new(&scene, true, false, true);
        assert!(!used.lobe);
        assert_eq!(map_texels(&scene, used).1[0], [0; 4]);
        // The per-material means sample nothing.
        assert!(!MapUse::new(&scene, true, true, false).any());
    }

    #[test]
    fn cpu_sampling_is_bilinear_in_the_footprints_level() {
        // Columns 0, 60, 120, 180 (linear). At the centre between texels 1 and 2 of row 0,
        // level 0 (a footprint of 1 texel): (60 + 120)/2.
        let t = texture(4, 1, false, |x, _| [x as u8 * 60; 3]);
        let uv = Vec2::new(0.5, 1.0 - 0.5);
        let lod0 = -(4.0f32).log2() / 2.0 - 1.0;
        let v = sample_map_cpu(&t, uv, lod0);
        assert!((v.x - 90.0 / 255.0).abs() < 1e-6, "{v}");
        // A footprint of the whole texture reads the 1×1 level, the mean of its halves'
        // means: ((0 + 60)/2 rounded, (120 + 180)/2) → (30 + 150)/2.
        let v = sample_map_cpu(&t, uv, 8.0);
        assert!((v.x - 90.0 / 255.0).abs() < 1.0 / 255.0, "{v}");
    }
}
