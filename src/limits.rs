//! The ranges of settings values: command-line flags (`cli::args`), scene files
//! (`scene::desc`), the viewer's panel (`app::panel`) and `render::check_render_settings` (run
//! by `Renderer::new` for every caller) all check against these, so a value is accepted or
//! refused with the same range and words everywhere. The ranges of the `[gi]`, `[post]` and
//! `[shadow]` keys live beside their key tables (`scene::gi_range`, `scene::post_range`,
//! `scene::shadow_range`); those here are the frame's other values. Plain data at the bottom
//! layer, using no other module.
//!
//! A [`Limit`] names the value three ways: its flag, its scene-file key (where a scene file
//! can give it) and what it is; an error from it names the one the user typed.

use std::fmt;
use std::ops::RangeInclusive;

/// The range of one settings value, inclusive at both ends unless `min_exclusive`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limit<T> {
    /// The command-line flag, e.g. `--gi-rays`.
    pub flag: &'static str,
    /// The scene-file key, e.g. `gi.rays`, where scene files take the value.
    pub key: Option<&'static str>,
    /// What the value is, for the message: "rays per pixel".
    pub what: &'static str,
    pub min: T,
    pub max: T,
    /// The minimum itself is refused (lengths that must be positive).
    pub min_exclusive: bool,
}

/// A value outside its [`Limit`]: `name` is the flag or key the user gave, `expected` says
/// what would be accepted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{name} = {value} is invalid; expected {expected}")]
pub struct LimitError {
    pub name: String,
    pub value: String,
    pub expected: String,
}

impl<T: Copy + PartialOrd + fmt::Display> Limit<T> {
    pub const fn new(
        flag: &'static str,
        key: Option<&'static str>,
        what: &'static str,
        min: T,
        max: T,
    ) -> Self {
        Self {
            flag,
            key,
            what,
            min,
            max,
            min_exclusive: false,
        }
    }

    /// The span `lo..=hi` cut to the limit: a panel slider's range, which can never offer a
    /// value the flags and scene files refuse. (With an exclusive minimum, `lo` must be above
    /// it.)
    pub fn slider(&self, lo: T, hi: T) -> RangeInclusive<T> {
        let lo = if lo < self.min { self.min } else { lo };
        let hi = if hi > self.max { self.max } else { hi };
        debug_assert!(
            self.contains(lo) && self.contains(hi),
            "{} slider",
            self.flag
        );
        lo..=hi
    }

    fn contains(&self, v: T) -> bool {
        let above = if self.min_exclusive {
            v > self.min
        } else {
            v >= self.min
        };
        above && v <= self.max
    }

    fn error(&self, name: &str, value: impl fmt::Display, kind: &str) -> LimitError {
        let open = if self.min_exclusive { "(" } else { "[" };
        LimitError {
            name: name.to_owned(),
            value: value.to_string(),
            expected: format!("{}, {kind} in {open}{}, {}]", self.what, self.min, self.max),
        }
    }
}

impl Limit<u32> {
    /// `v` (as typed: a TOML integer may be negative or huge) when in range, else the error
    /// naming `name`.
    pub fn check_as(&self, name: &str, v: i64) -> Result<u32, LimitError> {
        match u32::try_from(v) {
            Ok(u) if self.contains(u) => Ok(u),
            _ => Err(self.error(name, v, "an integer")),
        }
    }

    /// [`Self::check_as`] under the flag's name.
    pub fn check_flag(&self, v: u32) -> Result<u32, LimitError> {
        self.check_as(self.flag, i64::from(v))
    }
}

impl Limit<f32> {
    /// `v` when finite and in range, else the error naming `name`.
    pub fn check_as(&self, name: &str, v: f32) -> Result<f32, LimitError> {
        if v.is_finite() && self.contains(v) {
            Ok(v)
        } else {
            Err(self.error(name, v, "a finite number"))
        }
    }

    /// [`Self::check_as`] under the flag's name.
    pub fn check_flag(&self, v: f32) -> Result<f32, LimitError> {
        self.check_as(self.flag, v)
    }
}

/// Frame width and height: the renderer's images are at most 16384 texels on a side, the
/// `maxImageDimension2D` every Vulkan 1.3 desktop driver offers (lavapipe's too).
pub const WIDTH: Limit<u32> = Limit::new("--width", None, "a width in pixels", 1, 16384);
pub const HEIGHT: Limit<u32> = Limit::new("--height", None, "a height in pixels", 1, 16384);
/// Scene time: any finite number of seconds within ±1e9 (animations are evaluated in f32).
pub const TIME_S: Limit<f32> = Limit::new("--time", None, "a scene time in seconds", -1e9, 1e9);
/// The voxel grid's x/y resolution cap: one image texel per column, at most 16384 per side.
pub const VOXELS: Limit<u32> = Limit::new(
    "--voxels",
    Some("voxel.resolution"),
    "a voxel grid resolution (columns per side)",
    1,
    16384,
);
pub const VOXEL_LAYERS: Limit<u32> = Limit::new(
    "--voxel-layers",
    Some("voxel.layers"),
    "a number of depth layers of 128 voxels",
    1,
    64,
);
/// Sub-lights an area light is rendered with (`light::area`): each is a light with one shadow
/// view, and a frame has at most 64 of each (`render::gpu::MAX_LIGHTS`, `MAX_SHADOW_VIEWS`).
pub const AREA_SAMPLES: Limit<u32> = Limit::new(
    "--area-samples",
    Some("lights[].samples"),
    "sub-lights per area light",
    1,
    64,
);
/// Node-buffer capacity of the transparency lists in nodes per pixel (`render::oit_gather`):
/// 16 bytes a node, so 64 at 4K is 8 GiB, the most any device voxgi targets could hold.
pub const OIT_NODES_PER_PIXEL: Limit<u32> = Limit::new(
    "--oit-nodes-per-pixel",
    None,
    "transparent layers stored per pixel on average",
    1,
    64,
);
/// Hierarchy levels of a 16384² grid: 0..=14.
pub const DEBUG_LEVEL: Limit<u32> = Limit::new(
    "--debug-level",
    None,
    "a hierarchy level (0: the voxels)",
    0,
    14,
);
pub const DEBUG_STEPS_SCALE: Limit<u32> = Limit::new(
    "--debug-steps-scale",
    None,
    "a number of traversal steps shown white",
    1,
    1 << 20,
);

/// Stereo eye separation: 0 gives two identical eyes (allowed, a mono check); 1e3 m is beyond
/// any scene scale voxgi renders in f32.
pub const STEREO_SEPARATION_M: Limit<f32> = Limit::new(
    "--eye-separation",
    None,
    "an eye separation in meters",
    0.0,
    1e3,
);
/// Stereo convergence (zero-parallax) distance: positive, it divides the frustum shift.
pub const STEREO_CONVERGENCE_M: Limit<f32> = Limit {
    min_exclusive: true,
    ..Limit::new(
        "--convergence",
        None,
        "a convergence distance in meters",
        0.0,
        1e9,
    )
};
/// The orthographic camera's view height: positive (it divides the projection), at most the
/// size a scene's coordinates may have.
pub const ORTHO_HEIGHT_M: Limit<f32> = Limit {
    min_exclusive: true,
    ..Limit::new(
        "--ortho-height",
        Some("camera.ortho_height_m"),
        "a view height in meters",
        0.0,
        1e7,
    )
};

/// `voxgi sweep`'s ray-test comparison (`bench traverse`): ray lengths in the thesis's
/// test-box units, radius_m = r / 6 × the scene's largest extent. From r = 6√3 ≈ 10.4 on a ray
/// is longer than the grid's diagonal, so the cap only stops typos.
pub const TRAVERSE_RADIUS: Limit<f32> = Limit {
    min_exclusive: true,
    ..Limit::new(
        "--traverse-radii",
        None,
        "a ray length in test-box units",
        0.0,
        64.0,
    )
};
/// Marching samples per ray (1-bit and 3-bit rows each); 65536 is `bench traverse`'s cap.
pub const TRAVERSE_SAMPLES: Limit<u32> = Limit::new(
    "--traverse-samples",
    None,
    "marching samples per ray",
    1,
    65536,
);
/// The side of the CPU-traced G-buffer the rays start from: its cost is side² × the scene's
/// triangles (the atrium's voxels and 64² G-buffer took about 25 s on 2 shared cores, so 256²
/// takes minutes), and the ray buffers grow with it.
pub const TRAVERSE_GBUFFER: Limit<u32> = Limit::new(
    "--traverse-gbuffer",
    None,
    "a G-buffer side in pixels",
    8,
    256,
);
/// Rays per surface point: with the G-buffer's cap at most 256² × 64 = 4.2M rays, whose
/// 32-byte rays and results per test stay within a few GiB.
pub const TRAVERSE_RAYS: Limit<u32> =
    Limit::new("--traverse-rays", None, "rays per surface point", 1, 64);
/// Timed runs of every ray test.
pub const TRAVERSE_REPEATS: Limit<u32> = Limit::new(
    "--traverse-repeats",
    None,
    "timed runs per ray test",
    1,
    100,
);

#[cfg(test)]
mod tests {
    use super::*;

    /// Limits of the shape the settings tables use (`scene::post_settings::range`).
    const TAA_FRAMES: Limit<u32> = Limit::new(
        "--taa-frames",
        Some("post.taa_frames"),
        "a number of TAA frames",
        1,
        4096,
    );
    const EXPOSURE: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--exposure",
            Some("post.exposure"),
            "an exposure factor",
            0.0,
            1e6,
        )
    };
    const BLOOM_STRENGTH: Limit<f32> =
        Limit::new("--bloom", Some("post.bloom"), "a bloom strength", 0.0, 1.0);

    #[test]
    fn integers_are_checked_at_both_ends_and_against_overflow() {
        assert_eq!(TAA_FRAMES.check_flag(1), Ok(1));
        assert_eq!(TAA_FRAMES.check_flag(4096), Ok(4096));
        let e = TAA_FRAMES.check_flag(0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--taa-frames = 0 is invalid; expected a number of TAA frames, an integer in [1, 4096]"
        );
        assert!(TAA_FRAMES.check_flag(4097).is_err());
        // A TOML integer beyond u32 is refused, not wrapped.
        assert!(TAA_FRAMES
            .check_as("post.taa_frames", (1 << 32) + 5)
            .is_err());
        assert!(TAA_FRAMES.check_as("post.taa_frames", -1).is_err());
    }

    #[test]
    fn floats_refuse_nan_infinity_and_an_open_minimum() {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -1.0] {
            let e = EXPOSURE.check_flag(bad).unwrap_err();
            assert!(e.to_string().starts_with("--exposure = "), "{e}");
            assert!(e.to_string().contains("(0, 1000000]"), "{e}");
        }
        assert_eq!(EXPOSURE.check_flag(2.5), Ok(2.5));
        assert_eq!(BLOOM_STRENGTH.check_flag(0.0), Ok(0.0));
        assert!(EXPOSURE.check_as("post.exposure", 0.0).is_err());
    }

    #[test]
    fn stereo_parallax_refuses_nan_and_negative() {
        for bad in [f32::NAN, -0.01] {
            assert!(STEREO_SEPARATION_M.check_flag(bad).is_err());
            assert!(STEREO_CONVERGENCE_M.check_flag(bad).is_err());
        }
        assert!(STEREO_CONVERGENCE_M.check_flag(0.0).is_err());
        assert_eq!(STEREO_SEPARATION_M.check_flag(0.0), Ok(0.0));
        assert_eq!(STEREO_CONVERGENCE_M.check_flag(1.5), Ok(1.5));
    }
}
