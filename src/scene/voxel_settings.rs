//! The voxel grid's settings: plain data at the bottom, so that scene files (`[voxel]` tables),
//! the command line and the sweep share them with the voxelizer (`crate::voxel::gpu`, which
//! re-exports them). The `[voxel]` keys are declared once, in [`VoxelSettings::keys`]'s table
//! (`scene::schema`).

use super::schema::{choices, flag, toggle, Key, Kind, Settings};

/// The two voxelizers of docs/design/voxels.md.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Voxelizer {
    /// Exact conservative triangle/box test (`voxelize_triangles`), bit for bit the CPU
    /// reference.
    #[default]
    Triangle,
    /// The thesis's texture-atlas splatting with automatic atlases (one per OBJ sequence);
    /// sequences whose frames differ in topology still use the triangle voxelizer.
    // See `voxel::gpu_atlas` (no intra-doc link: clap shows this text in --help).
    Atlas,
}

/// How the scene is voxelized when something needs voxels (a GI method, the emitters' or the
/// environment's direct light, a voxel debug view), or always when a command line gives a
/// `[voxel]` key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelSettings {
    /// Cap on the x/y resolution; voxels are near-cubic (`voxel::VoxelGrid::around`).
    pub max_res_xy: u32,
    /// Depth layers of 128 voxels.
    pub layers: u32,
    /// Voxelize static geometry every frame too (to measure the full cost) instead of once.
    pub revoxelize_static: bool,
    /// Which voxelizer sets the bits.
    pub voxelizer: Voxelizer,
}

impl Default for VoxelSettings {
    fn default() -> Self {
        Self {
            max_res_xy: 128,
            layers: 1,
            revoxelize_static: false,
            voxelizer: Voxelizer::Triangle,
        }
    }
}

macro_rules! key {
    ($($t:tt)*) => {
        crate::settings_key!(VoxelSettings; $($t)*)
    };
}

/// Every `[voxel]` key: the scene file's key, the path `--set` and the sweep use, its range,
/// its flag and its field.
static VOXEL_KEYS: [Key<VoxelSettings>; 4] = [
    key!(
        "voxel.resolution",
        Kind::Count(crate::limits::VOXELS),
        "Voxel grid resolution: at most N columns per side (voxels are near-cubic, so the \
         scene's longest side gets N); the flag voxelizes even when nothing needs voxels",
        flag("voxels", "N"),
        max_res_xy
    ),
    key!(
        "voxel.layers",
        Kind::Count(crate::limits::VOXEL_LAYERS),
        "Depth layers of 128 voxels of the voxel grid (the depth is 128 × layers)",
        flag("voxel-layers", "N"),
        layers
    ),
    key!("voxel.voxelizer", Kind::Choice(choices::<Voxelizer>),
        "Voxelizer: exact triangle/box test, or the thesis's texture-atlas splatting with \
         automatic atlases (applies to GI and the voxel debug views)",
        flag("voxelizer", "VOXELIZER"), choice Voxelizer, voxelizer),
    key!(
        "voxel.revoxelize",
        Kind::Bool,
        "Voxelize static geometry every frame too (measures the full voxelization)",
        toggle("revoxelize"),
        revoxelize_static
    ),
];

impl Settings for VoxelSettings {
    const TABLE: &'static str = "voxel";
    fn keys() -> &'static [Key<Self>] {
        &VOXEL_KEYS
    }
}
