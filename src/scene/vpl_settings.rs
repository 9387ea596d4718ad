//! Parameters of the VPL method (`--gi vpl`, Thiedemann 2010, Ch. 7): plain data, read from
//! flags, the scene's `[gi]` table and the viewer's panel (the passes are in `gi/vpl.rs`).

/// Visibility of a VPL from a receiver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum VplVisibility {
    /// The voxel segment test with offsets at both ends (thesis §5.3, §7.3).
    #[default]
    Voxel,
    /// Every VPL is visible (v = 1): the cost and the error of visibility, measured.
    None,
}

/// How the frame is shaded with the VPLs (Thiedemann 2010, §7.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum VplShading {
    /// One pass, every VPL of the pixel's set in a loop.
    #[default]
    Gather,
    /// One pass per VPL of a row, each adding its light to the image (the thesis's additive
    /// splatting, there with blending).
    Splat,
}

/// What the first-bounce flux of a light is divided among (Thiedemann 2010, §7.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum VplNormalize {
    /// All K samples of the light's emission domain, valid or not: the flux of samples that
    /// hit nothing leaves the scene, as it does in Mitsuba (unbiased).
    #[default]
    All,
    /// Only the samples that hit geometry (the thesis's renormalization): each VPL's flux is
    /// multiplied by K / valid count; equal to `all` where nothing misses, brighter where light
    /// leaves the scene.
    Valid,
}

/// How a spot light's first-bounce directions are sampled (Thiedemann 2010, §7.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum VplSpotSampling {
    /// Uniform in solid angle on the cone: every sample carries the same weight Ω / K.
    #[default]
    SolidAngle,
    /// Uniform in the disk the cone cuts from the spot's image plane, as the thesis does;
    /// each sample weighted by the solid angle its area covers, π tan²α cos³θ / K.
    Disk,
}

/// Parameters of the VPL method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VplSettings {
    /// VPLs per interleaving set and light (K).
    pub per_set: u32,
    /// Interleaving pattern N×M: N·M sets, each shading one pixel of every N×M tile.
    pub pattern: [u32; 2],
    /// d_min of E = I cosθ_VPL cosθ_P / (d_min + d²) (thesis §7.3), which bounds the
    /// singularity of a VPL next to a receiver, as a distance in voxel diagonals h:
    /// d_min = (d_min_voxels · h)² m². Relative to the grid, so that a scene renders the same
    /// in millimeters or kilometers (tests/extremes.rs).
    pub d_min_voxels: f32,
    /// The roughness floor of glossy receivers: a GGX pixel's lobe is evaluated toward the
    /// VPLs with roughness max(r, this), a Phong pixel's with its exponent capped at the
    /// matching 2/r⁴ − 2. It bounds the peak of the receiver's lobe as d_min bounds 1/d²
    /// (a finite VPL set cannot light a sharp lobe smoothly), biasing only smoother receivers.
    pub min_roughness: f32,
    pub visibility: VplVisibility,
    /// VPL generations: 1 = the lights' direct light reflected once, 2 adds one voxel ray per
    /// VPL (the thesis's maximum), up to [`VplSettings::MAX_BOUNCES`].
    pub bounces: u32,
    pub shading: VplShading,
    pub normalize: VplNormalize,
    pub spot_sampling: VplSpotSampling,
    /// Debug view: draw every VPL as a dot over the lit image (`gi_vpl_points`).
    pub show: bool,
}

impl VplSettings {
    /// The most VPLs per set and light, and the largest pattern side.
    pub const MAX_PER_SET: u32 = crate::limits::VPLS.max;
    pub const MAX_PATTERN: u32 = crate::limits::VPL_PATTERN_SIDE.max;
    /// The most VPL bounces (each adds one ray per VPL and a row segment).
    pub const MAX_BOUNCES: u32 = crate::limits::VPL_BOUNCES.max;
}

impl Default for VplSettings {
    fn default() -> Self {
        Self {
            per_set: 16,
            pattern: [4, 4],
            d_min_voxels: 8.0,
            min_roughness: 0.4,
            visibility: VplVisibility::Voxel,
            bounces: 2,
            shading: VplShading::Gather,
            normalize: VplNormalize::All,
            spot_sampling: VplSpotSampling::SolidAngle,
            show: false,
        }
    }
}

/// VPL settings given by a scene's `[gi]` table or by flags; `None`: not given there
/// (see [`crate::scene::resolve_gi`] for the precedence).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VplOverrides {
    pub per_set: Option<u32>,
    pub pattern: Option<[u32; 2]>,
    pub bounces: Option<u32>,
    pub d_min_voxels: Option<f32>,
    pub min_roughness: Option<f32>,
    pub visibility: Option<VplVisibility>,
    pub normalize: Option<VplNormalize>,
    pub spot_sampling: Option<VplSpotSampling>,
}

impl VplOverrides {
    /// Field by field: `self`'s value where given, else `fallback`'s.
    pub fn or(self, fallback: VplOverrides) -> VplOverrides {
        VplOverrides {
            per_set: self.per_set.or(fallback.per_set),
            pattern: self.pattern.or(fallback.pattern),
            bounces: self.bounces.or(fallback.bounces),
            d_min_voxels: self.d_min_voxels.or(fallback.d_min_voxels),
            min_roughness: self.min_roughness.or(fallback.min_roughness),
            visibility: self.visibility.or(fallback.visibility),
            normalize: self.normalize.or(fallback.normalize),
            spot_sampling: self.spot_sampling.or(fallback.spot_sampling),
        }
    }

    /// `base` with the given values replaced.
    pub fn apply(&self, base: VplSettings) -> VplSettings {
        VplSettings {
            per_set: self.per_set.unwrap_or(base.per_set),
            pattern: self.pattern.unwrap_or(base.pattern),
            bounces: self.bounces.unwrap_or(base.bounces),
            d_min_voxels: self.d_min_voxels.unwrap_or(base.d_min_voxels),
            min_roughness: self.min_roughness.unwrap_or(base.min_roughness),
            visibility: self.visibility.unwrap_or(base.visibility),
            normalize: self.normalize.unwrap_or(base.normalize),
            spot_sampling: self.spot_sampling.unwrap_or(base.spot_sampling),
            shading: base.shading,
            show: base.show,
        }
    }
}

/// The names of [`VplVisibility`] in scene files and on the command line.
pub const VISIBILITY_NAMES: [(&str, VplVisibility); 2] = [
    ("voxel", VplVisibility::Voxel),
    ("none", VplVisibility::None),
];

/// The names of [`VplNormalize`] in scene files and on the command line.
pub const NORMALIZE_NAMES: [(&str, VplNormalize); 2] =
    [("all", VplNormalize::All), ("valid", VplNormalize::Valid)];

/// The names of [`VplSpotSampling`] in scene files and on the command line.
pub const SPOT_SAMPLING_NAMES: [(&str, VplSpotSampling); 2] = [
    ("solid-angle", VplSpotSampling::SolidAngle),
    ("disk", VplSpotSampling::Disk),
];

/// Parses `--vpl-pattern NxM` (e.g. `4x4`).
pub fn parse_pattern(s: &str) -> Result<[u32; 2], String> {
    let bad = || {
        format!(
            "expected NxM with N and M in [1, {}], e.g. 4x4",
            VplSettings::MAX_PATTERN
        )
    };
    let (a, b) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let n: u32 = a.trim().parse().map_err(|_| bad())?;
    let m: u32 = b.trim().parse().map_err(|_| bad())?;
    let ok = |v: u32| (1..=VplSettings::MAX_PATTERN).contains(&v);
    if ok(n) && ok(m) {
        Ok([n, m])
    } else {
        Err(bad())
    }
}
