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
    pub const MAX_PER_SET: u32 = super::gi_range::VPLS.max;
    pub const MAX_PATTERN: u32 = super::gi_range::VPL_PATTERN_SIDE.max;
    /// The most VPL bounces (each adds one ray per VPL and a row segment).
    pub const MAX_BOUNCES: u32 = super::gi_range::VPL_BOUNCES.max;
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
