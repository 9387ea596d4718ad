//! Opacity in the voxel grid: stochastic coverage.
//!
//! A binary voxel is either a wall or nothing, so a surface of opacity α (MTL `d`, TOML
//! `opacity`, glTF base colour alpha) cannot be stored as a fraction. Instead the voxels it
//! covers are set with probability α, decided per cell of [`CELL_VOXELS`]³ voxels by a hash of
//! the cell's address and the object (stochastic transparency, Enderton et al. 2010,
//! "Stochastic Transparency", §3, applied to voxels instead of pixels). The decision is a pure
//! function of the voxel and the object, so it does not change from frame to frame (no
//! flicker) and the bit voxelizer and the attribute volumes agree voxel by voxel. α = 0 sets
//! no voxel and α = 1 takes no decision at all (opaque scenes are voxelized bit for bit as
//! before).
//!
//! Why cells and not single voxels: a ray crossing a pane one voxel thick at angle θ to its
//! normal moves tan θ voxels sideways inside it and so meets about
//! 1 + tan θ (|cos φ| + |sin φ|) voxels of the pane, each an independent decision; with one
//! decision per voxel a 50% pane would pass 50% of the rays along its normal but only 22% of
//! cosine-distributed rays (39% of those within 30° of the normal). With cells of B voxels a
//! ray meets 1 + tan θ (|cos φ| + |sin φ|) / B cells: B = 8 passes 50% along the normal, 49%
//! within 30° and 44% of cosine-distributed rays (the midpoint quadrature of
//! `tests::oblique_rays_meet_more_cells`). The price is a coarser pattern: a pane's coverage
//! varies in blocks of 8 voxels. A pane lying exactly on a voxel face is voxelized two voxels
//! thick (the conservative test sets both sides); both usually lie in one cell and share its
//! decision.
//!
//! The object, not the triangle, seeds the hash: the triangles of one pane that share a voxel
//! along their common edge make one decision, not two (two draws would set it with
//! probability 1 − (1 − α)², darkening the seams). Two different panes in one voxel decide
//! independently. The seed is a hash of the object's name, so the voxelizer's copy of the
//! moving objects (a scene of its own) seeds them as the whole scene does; objects that share
//! a name share their pattern.
//!
//! What is supported: the material's constant opacity, and per-texel alpha (glTF base colour
//! alpha, MTL `map_d`) as its mean over the texture ([`crate::scene::Material::coverage_opacity`]:
//! the open fraction of a cutout, the mean alpha of a blend map). A voxel spans many texels, so
//! a leaf texture that is 40% open keeps 40% of the leaves' voxels, at hashed places rather than
//! the texture's holes; the rasterizing passes (G-buffer, shadow and light maps) test each
//! texel.
//!
//! The GPU twin is `glsl/include/voxel_coverage.glsl`; both compute the same integer hash, so
//! their decisions are identical.

use glam::UVec3;

use crate::scene::{Object, Scene};

/// One triangle's coverage rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coverage {
    /// 1 − opacity, computed once in f32: a voxel is set where its cell's uniform hash value
    /// is at least this, so the CPU and the GPU compare the very same two numbers.
    pub transparency: f32,
    /// The object's hash seed, below 2²⁴ (exact in the f32 the GPU triangle carries it in).
    pub seed: u32,
}

impl Coverage {
    /// Sets every voxel the triangle touches (and takes no decision).
    pub const OPAQUE: Self = Self {
        transparency: 0.0,
        seed: 0,
    };

    /// The rule for a triangle of the object named `object` whose material has `opacity`
    /// (clamped to [0, 1]; NaN counts as opaque, as the loader's default).
    pub fn new(object: &str, opacity: f32) -> Self {
        if opacity.is_nan() || opacity >= 1.0 {
            return Self::OPAQUE;
        }
        Self {
            transparency: 1.0 - opacity.max(0.0),
            seed: name_seed(object),
        }
    }

    /// True when every touched voxel is set (opacity 1).
    pub fn is_opaque(&self) -> bool {
        self.transparency <= 0.0
    }

    /// Whether the triangle sets voxel `v` (x, y, depth index) that it touches.
    pub fn covers(&self, v: UVec3) -> bool {
        self.is_opaque() || unit_hash(v, self.seed) >= self.transparency
    }

    /// The `w` components the GPU triangle carries (`v[0].w`, `v[1].w`).
    pub fn gpu_w(&self) -> [f32; 2] {
        [self.transparency, self.seed as f32]
    }
}

/// Edge of the cubes of voxels that share one coverage decision (`COVERAGE_CELL_SHIFT` in
/// `voxel_coverage.glsl` is its log2).
pub const CELL_VOXELS: u32 = 8;

/// The PCG hash (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering", §2 and the
/// `pcg` listing): one 32-bit state step and its output permutation. Its wrapping integer
/// arithmetic is the same in Rust and GLSL.
fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Uniform in [0, 1) on a 2⁻²⁴ lattice (exact in f32) for the cell of voxel `v` and `seed`:
/// nested one-dimensional PCG, the paper's recipe for several inputs (§3).
fn unit_hash(v: UVec3, seed: u32) -> f32 {
    let c = v / CELL_VOXELS;
    let h = pcg(c
        .x
        .wrapping_add(pcg(c.y.wrapping_add(pcg(c.z.wrapping_add(pcg(seed)))))));
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// FNV-1a of the name, folded to 24 bits.
fn name_seed(name: &str) -> u32 {
    let h = name.bytes().fold(0x811c_9dc5_u32, |h, b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    });
    ((h >> 24) ^ h) & 0x00ff_ffff
}

/// The coverage of every triangle of the scene's objects at `t_s`, in the order of
/// [`super::gpu::scene_triangles`] (`dynamic` selects the same objects).
pub fn scene_coverage(scene: &Scene, t_s: f32, dynamic: bool) -> Vec<Coverage> {
    scene
        .objects
        .iter()
        .filter(|o| (o.dynamic || o.is_animated()) == dynamic)
        .flat_map(|o| object_coverage(scene, o, o.mesh_at(t_s)))
        .collect()
}

/// The coverage of each triangle of `mesh` drawn as `object`: its submesh's material (the
/// object's override where it has one) decides. No triangles for a missing mesh.
pub fn object_coverage(scene: &Scene, object: &Object, mesh: usize) -> Vec<Coverage> {
    let Some(mesh) = scene.meshes.get(mesh) else {
        return Vec::new();
    };
    let mut out = vec![Coverage::OPAQUE; mesh.indices.len() / 3];
    for (si, sub) in mesh.submeshes.iter().enumerate() {
        let material = object.materials.get(si).copied().unwrap_or(sub.material);
        let opacity = scene
            .materials
            .get(material)
            .map_or(1.0, |m| m.coverage_opacity(&scene.textures));
        let c = Coverage::new(&object.name, opacity);
        let first = sub.first_index as usize / 3;
        let count = sub.index_count as usize / 3;
        for slot in out.iter_mut().skip(first).take(count) {
            *slot = c;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opaque_and_clear_are_exact() {
        let v = UVec3::new(3, 4, 5);
        assert!(Coverage::new("a", 1.0).is_opaque());
        assert_eq!(Coverage::new("a", 1.0), Coverage::OPAQUE);
        assert_eq!(Coverage::new("a", f32::NAN), Coverage::OPAQUE);
        // α = 0: transparency 1, and the hash never reaches 1.
        let clear = Coverage::new("a", 0.0);
        let all = (0..32u32).flat_map(|x| (0..32u32).map(move |k| UVec3::new(x, 7, k)));
        assert!(all.clone().all(|v| !clear.covers(v)));
        assert!(all.clone().all(|v| Coverage::OPAQUE.covers(v)));
        assert!(
            Coverage::new("a", -1.0).transparency == 1.0 && !Coverage::new("a", -1.0).covers(v)
        );
    }

    #[test]
    fn the_hash_sets_the_chosen_fraction_of_cells() {
        // 64³ = 262,144 cells, independent decisions with p = 0.5: the standard deviation of
        // the fraction is 0.5 / 512 ≈ 0.001, so ±0.005 is five of them.
        let c = Coverage::new("pane", 0.5);
        let n = 64u32;
        let cell = |i: u32| UVec3::new(i % n, i / n % n, i / (n * n)) * CELL_VOXELS;
        let set = (0..n * n * n).filter(|&i| c.covers(cell(i))).count();
        let fraction = set as f64 / f64::from(n * n * n);
        assert!((fraction - 0.5).abs() < 0.005, "fraction {fraction}");
        // Every voxel of a cell takes the cell's decision.
        for i in 0..512 {
            let base = cell(i);
            let first = c.covers(base);
            let b = CELL_VOXELS;
            let mut all = (0..b * b * b).map(|k| base + UVec3::new(k % b, k / b % b, k / (b * b)));
            assert!(all.all(|v| c.covers(v) == first), "cell {base}");
        }
    }

    /// The transmission of a slab one voxel thick whose cells of B voxels are each clear with
    /// probability q, for rays cosine-distributed about its normal within sin²θ < u_max,
    /// entering at a uniformly random point: a ray moves a = tan θ |cos φ| / B cells along x
    /// inside the slab, crossing ⌊a⌋ cell faces and one more with probability frac(a), each a
    /// further decision (likewise along z), so it passes with q · E_x · E_z,
    /// E = q^⌊a⌋ (1 − frac(a) + frac(a) q); midpoint rule in u = sin²θ (uniform under the
    /// cosine density) and φ.
    fn slab_transmission(q: f64, b: f64, u_max: f64) -> f64 {
        let (n_u, n_phi) = (512, 32);
        let crossings = |a: f64| {
            let f = a.floor();
            q.powf(f) * (1.0 - (a - f) + (a - f) * q)
        };
        let mut sum = 0.0;
        for i in 0..n_u {
            let u = (f64::from(i) + 0.5) / f64::from(n_u) * u_max;
            let tan = (u / (1.0 - u)).sqrt() / b;
            for j in 0..n_phi {
                let phi = (f64::from(j) + 0.5) / f64::from(n_phi) * std::f64::consts::FRAC_PI_2;
                sum += q * crossings(tan * phi.cos()) * crossings(tan * phi.sin());
            }
        }
        sum / f64::from(n_u * n_phi)
    }

    #[test]
    fn oblique_rays_meet_more_cells() {
        // The numbers the module documentation quotes, for a 50% pane.
        let b = f64::from(CELL_VOXELS);
        let cosine = slab_transmission(0.5, b, 1.0);
        let within_30 = slab_transmission(0.5, b, 0.25);
        assert!((cosine - 0.44).abs() < 0.005, "{cosine}");
        assert!((within_30 - 0.49).abs() < 0.005, "{within_30}");
        assert!((slab_transmission(0.5, 1.0, 1.0) - 0.22).abs() < 0.005);
        assert!((slab_transmission(0.5, 1.0, 0.25) - 0.39).abs() < 0.005);
        // Along the normal (u_max → 0) one decision: exactly q.
        assert!((slab_transmission(0.5, b, 1e-9) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn objects_decide_independently() {
        // Two panes of opacity 0.5 in the same voxels: with independent decisions a voxel is
        // set by either with probability 1 − q² = 0.75 (0.5 if they shared the pattern).
        let (a, b) = (Coverage::new("left", 0.5), Coverage::new("right", 0.5));
        assert_ne!(a.seed, b.seed);
        let q = f64::from(a.transparency);
        let n = 64u32;
        let either = (0..n * n * n)
            .map(|i| UVec3::new(i % n, i / n % n, i / (n * n)) * CELL_VOXELS)
            .filter(|&v| a.covers(v) || b.covers(v))
            .count();
        let fraction = either as f64 / f64::from(n * n * n);
        assert!(
            (fraction - (1.0 - q * q)).abs() < 0.005,
            "fraction {fraction}, q {q}"
        );
    }

    #[test]
    fn gpu_w_is_exact() {
        let c = Coverage::new("some object", 0.3);
        let [t, s] = c.gpu_w();
        assert_eq!(t, c.transparency);
        assert_eq!(s as u32, c.seed);
        assert!(c.seed < 1 << 24);
    }
}
