//! The GI methods, one file each: a [`MethodSpec`] that states what the rest of the program
//! asks about the method (its name, whether it accumulates, what it reads, its panel section,
//! its sweep keys) and builds its passes. [`GiMethod::spec`] below is the registry; the
//! `--gi` values, the scene files' `[gi] method` names, the panel's list, the viewer's `G`
//! cycle and the sweep's methods all come from the specs. Nothing else matches on the method:
//! code that needs a fact about one asks its spec.
//!
//! Adding a method: a file here with its `SPEC` (and its passes, in a file of their own when
//! they are large), its `mod` line, its arm in [`GiMethod::spec`], and its variant in the
//! enum, which lives with the settings in `scene` (the lowest layer that holds a method;
//! `docs/design/gi-methods.md`).

mod hemisphere;
mod none;
mod pathtrace;
mod ssgi;
mod vpl;

use super::{GiMethodPasses, GiSettings, GiTarget};
use crate::scene::Scene;
use crate::vk::{Context, ImageDesc, VkError};

pub use crate::scene::GiMethod;

impl GiMethod {
    /// What the program knows about the method: its file's spec. The registry: one arm per
    /// method, in the order of [`GiMethod::ALL`] (exhaustive, so a new variant does not
    /// compile until its spec is named here).
    pub fn spec(self) -> &'static MethodSpec {
        match self {
            GiMethod::None => &none::SPEC,
            GiMethod::Hemisphere => &hemisphere::SPEC,
            GiMethod::Pathtrace => &pathtrace::SPEC,
            GiMethod::Vpl => &vpl::SPEC,
            GiMethod::Ssgi => &ssgi::SPEC,
        }
    }
}

/// Builds a method's passes for the settings and the frame they are made for.
pub(in crate::gi) type BuildPasses =
    fn(&Context, &GiSettings, &GiTarget<'_>) -> Result<Box<dyn GiMethodPasses>, VkError>;

/// The rays a method traces from a transparent layer's fragments (`oit_gather`'s variants),
/// each reading what the method's own pass reads at a hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerIndirect {
    /// The path tracer's voxel paths (`oit_gather_indirect`): the attribute volumes.
    Paths,
    /// The hemisphere method's rays, hits from the reflective light maps
    /// (`oit_gather_hemisphere`; with emitters `oit_gather_hemisphere_emission`, which also
    /// reads the emission and normal volumes).
    LightMaps,
    /// The hemisphere method's rays, hits from the direct-radiance volume
    /// (`oit_gather_hemisphere_volume`) and the attribute volumes.
    RadianceVolume,
    /// The VPL method's gather over every interleaved set of the frame's VPLs
    /// (`oit_gather_vpl`): the VPL buffer, with the gather's own parameters
    /// ([`crate::gi::vpl::GpuVplGatherPush`]).
    Vpls,
}

impl LayerIndirect {
    /// Whether the layers' rays read the attribute volumes: the paths and the radiance
    /// volume's hits always, the light maps' hits for the emitters' light in scenes with
    /// emitters, the VPL gather never (the VPLs carry what their passes read).
    pub fn reads_attribute_volumes(self, scene: &Scene) -> bool {
        match self {
            LayerIndirect::Paths | LayerIndirect::RadianceVolume => true,
            LayerIndirect::LightMaps => scene.has_emission(),
            LayerIndirect::Vpls => false,
        }
    }
}

/// What the program asks about a GI method, answered in the method's file.
pub struct MethodSpec {
    /// Its name in `--gi`, in a scene's `[gi] method`, in the panel and in the sweep's CSV.
    pub name: &'static str,
    /// One line for `--help`.
    pub description: &'static str,
    /// A few words for the list of choices in error messages ("one bounce").
    pub summary: &'static str,
    /// A headless render runs `accumulate_frames` frames for its image (the method converges
    /// or adds bounces over frames); otherwise one frame is the image.
    pub accumulates: bool,
    /// `gi.temporal` accumulates the method's indirect light over frames with reprojection
    /// (`gi_temporal`): its passes advance their samples by [`super::gi_common::GiShared::seed`].
    pub temporal: bool,
    /// The method traces rays in the voxel grid and reads radiance from the reflective light
    /// maps: the frame voxelizes and renders the light maps.
    pub needs_voxels: bool,
    /// The method reads the area lights' (paraboloid) light maps too.
    pub reads_area_light_maps: bool,
    /// Which emissive surfaces' light the method's own passes bring to a pixel's surface
    /// (its first bounce off them). What it does not bring, the `direct_emitters` pass
    /// samples (`render::direct_emitters::sampled_light`), so that every emitter is counted
    /// once.
    pub brings_emitters: EmitterReach,
    /// The method's own rays bring the environment's light to a pixel's surface (rays that
    /// leave the voxel grid read it); otherwise `direct_emitters` samples it.
    pub brings_environment: bool,
    /// The method reads the albedo and normal volumes (and with them, in scenes with emitters,
    /// the emission volume).
    pub attribute_volumes: fn(&GiSettings, &Scene) -> bool,
    /// The method's hits sample the Phong and GGX lobes, so the attribute volumes carry the
    /// material volume.
    pub material_volume: fn(&GiSettings) -> bool,
    /// How transparent layers drawn as per-pixel lists (`--transparency oit`) get the
    /// method's indirect light: `oit_gather` traces the method's rays from each fragment
    /// (`glsl/include/oit_gather_body.glsl`). `None`: they get direct light only.
    pub transparent_indirect: fn(&GiSettings) -> Option<LayerIndirect>,
    /// The frame-sized history images the method keeps per eye, for the renderer's memory
    /// check: `(settings, size, glossy)` where `glossy` says the scene has Phong or GGX
    /// materials.
    pub history: fn(&GiSettings, (u32, u32), bool) -> Vec<ImageDesc>,
    /// The interleaved-sampling tile the geometry-aware filter undoes (`[1, 1]`: none).
    pub filter_tile: fn(&GiSettings) -> [u32; 2],
    /// Why a one-frame multiview stereo frame cannot render the method (`None`: it can).
    pub multiview_blocker: Option<&'static str>,
    /// Why an orthographic camera cannot render the method, and what to do instead (`None`:
    /// it can).
    pub orthographic_blocker: Option<Refusal>,
    /// The `voxgi render` flags (without `--`) a sweep grid varies for this method; a key is
    /// left out of the other methods' configurations, so that none is measured twice.
    pub sweep_keys: &'static [&'static str],
    /// `voxgi sweep` runs the method when `--methods` is not given.
    pub swept_by_default: bool,
    /// The method's colour in the sweep's Pareto plot.
    pub plot_colour: &'static str,
    /// One line about the method and its parameters, for the viewer's log.
    pub describe: fn(&GiSettings) -> String,
    /// Draws the method's own section of the viewer's panel; `frames` is what the indirect
    /// light has accumulated (`None`: GI off).
    pub panel: fn(&mut egui::Ui, &mut GiSettings, Option<u32>),
    /// Builds the method's passes.
    pub(in crate::gi) build: BuildPasses,
}

/// Which emitters' light a GI method brings to the surfaces it lights
/// ([`MethodSpec::brings_emitters`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmitterReach {
    /// None: the direct-light pass samples every emitter.
    Nothing,
    /// Only the emitting points the camera sees (screen-space GI gathers the frame's lit
    /// colour, emission included): the direct-light pass samples the others.
    OnScreen,
    /// Every emitter, on screen or not: the direct-light pass samples none.
    All,
}

/// A combination a renderer refuses, in the words of [`crate::render::RenderError`].
#[derive(Clone, Copy, Debug)]
pub struct Refusal {
    /// The flag refused.
    pub what: &'static str,
    pub why: &'static str,
    pub instead: &'static str,
}

impl clap::ValueEnum for GiMethod {
    fn value_variants<'a>() -> &'a [Self] {
        GiMethod::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let spec = self.spec();
        Some(clap::builder::PossibleValue::new(spec.name).help(spec.description))
    }
}

impl GiMethod {
    /// The method's name as `--gi` and a scene's `method` spell it.
    pub fn name(self) -> &'static str {
        self.spec().name
    }

    /// The method named `name` (exactly as `--gi` spells it).
    pub fn from_name(name: &str) -> Option<GiMethod> {
        GiMethod::ALL.iter().copied().find(|m| m.name() == name)
    }

    /// The method after this one in the registry (wrapping): the viewer's `G` key.
    pub fn next(self) -> GiMethod {
        let i = GiMethod::ALL.iter().position(|&m| m == self).unwrap_or(0);
        GiMethod::ALL[(i + 1) % GiMethod::ALL.len()]
    }

    /// Whether the method traces rays in the voxel grid ([`MethodSpec::needs_voxels`]).
    pub fn needs_voxels(self) -> bool {
        self.spec().needs_voxels
    }

    /// Every method's name with its summary, for error messages: `"none" (direct light
    /// only), "hemisphere" (one bounce), …`.
    pub fn choices() -> String {
        let names: Vec<String> = GiMethod::ALL
            .iter()
            .map(|m| format!("\"{}\" ({})", m.name(), m.spec().summary))
            .collect();
        names.join(", ")
    }

    /// The keys a sweep grid may vary: every method's [`MethodSpec::sweep_keys`], each once,
    /// in registry order.
    pub fn sweep_keys() -> Vec<&'static str> {
        let mut keys: Vec<&'static str> = Vec::new();
        for m in GiMethod::ALL {
            for k in m.spec().sweep_keys {
                if !keys.contains(k) {
                    keys.push(k);
                }
            }
        }
        keys
    }
}

/// The spatial filter in a method's one-line description: "filter R×P" (the geometry-aware
/// filter's radius and pass pairs) or "svgf ×P" (SVGF's iterations).
fn filter_label(gi: &GiSettings) -> String {
    match gi.filter {
        crate::scene::GiFilterKind::Geometric => {
            format!("filter {}×{}", gi.filter_radius, gi.filter_passes)
        }
        crate::scene::GiFilterKind::Svgf if gi.filter_radius == 0 => "filter 0".to_string(),
        crate::scene::GiFilterKind::Svgf => format!("svgf ×{}", gi.filter_passes),
    }
}

/// The panel's rays-per-pixel slider (`gi.rays`), for the methods that shoot rays per pixel.
fn rays_slider(ui: &mut egui::Ui, gi: &mut GiSettings) {
    crate::panel_keys::key_slider(ui, gi, "gi.rays", (1.0, 256.0), true, "rays / pixel");
}

/// The panel's temporal-accumulation switch and history length (`gi.temporal`,
/// `gi.temporal_frames`), for the methods whose spec has `temporal`.
fn temporal_controls(ui: &mut egui::Ui, gi: &mut GiSettings) {
    use crate::panel_keys::{key_checkbox, key_slider};
    key_checkbox(ui, gi, "gi.temporal", "temporal accumulation");
    if gi.temporal {
        key_slider(
            ui,
            gi,
            "gi.temporal_frames",
            (1.0, 256.0),
            true,
            "history frames",
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    #[test]
    fn names_are_unique_and_round_trip() {
        for &m in GiMethod::ALL {
            assert_eq!(GiMethod::from_name(m.name()), Some(m));
            assert_eq!(GiMethod::from_str(m.name(), true), Ok(m), "clap's name");
        }
        let names: std::collections::HashSet<_> = GiMethod::ALL.iter().map(|m| m.name()).collect();
        assert_eq!(names.len(), GiMethod::ALL.len());
    }

    #[test]
    fn the_g_key_visits_every_method_once() {
        let mut m = GiMethod::default();
        let mut seen = Vec::new();
        for _ in GiMethod::ALL {
            seen.push(m);
            m = m.next();
        }
        assert_eq!(m, GiMethod::default());
        assert_eq!(seen, GiMethod::ALL);
    }

    #[test]
    fn a_method_without_voxels_reads_no_voxel_volumes() {
        let s = GiSettings::default();
        let scene = crate::scene::builtin("cornell").expect("a built-in");
        for &m in GiMethod::ALL {
            let spec = m.spec();
            let settings = GiSettings { method: m, ..s };
            if !spec.needs_voxels {
                assert!(
                    !(spec.attribute_volumes)(&settings, &scene),
                    "{}",
                    spec.name
                );
                assert!(!spec.reads_area_light_maps, "{}", spec.name);
            }
        }
    }

    /// No `match` over the methods outside the registry has a catch-all arm: a new method
    /// must not fall through one unnoticed. Scans `src/` for `match` blocks whose arms name
    /// `GiMethod::` and fails on a `_ =>` arm at the block's own depth.
    #[test]
    fn no_match_over_methods_has_a_catch_all_arm() {
        let (mut found, mut files) = (Vec::new(), 0);
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut dirs = vec![root];
        while let Some(dir) = dirs.pop() {
            for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
                let path = entry.path();
                if path.is_dir() {
                    dirs.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path).unwrap_or_default();
                    files += 1;
                    for line in catch_all_matches_over_methods(&text) {
                        found.push(format!("{}:{line}", path.display()));
                    }
                }
            }
        }
        assert!(files > 100, "the scan read {files} files of src/");
        assert!(
            found.is_empty(),
            "a `_ =>` arm in a match over GiMethod (ask the method's spec instead): {found:?}"
        );
    }

    /// The lines (1-based) of the `match` blocks in `text` that name `GiMethod::` in an arm
    /// and have a `_ =>` arm.
    fn catch_all_matches_over_methods(text: &str) -> Vec<usize> {
        let bytes = text.as_bytes();
        let mut out = Vec::new();
        let mut from = 0;
        while let Some(i) = text[from..].find("match ").map(|i| i + from) {
            from = i + 6;
            let word_start =
                i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
            let Some(open) = text[i..].find('{').map(|o| o + i) else {
                break;
            };
            if !word_start {
                continue;
            }
            // The block's arms at depth 1.
            let (mut depth, mut end) = (0usize, text.len());
            let mut body = String::new();
            for (k, c) in text[open..].char_indices() {
                match c {
                    '{' | '(' | '[' => depth += 1,
                    '}' | ')' | ']' => {
                        depth -= 1;
                        if depth == 0 {
                            end = open + k;
                            break;
                        }
                    }
                    _ => {}
                }
                if depth == 1 {
                    body.push(c);
                } else if depth > 1 && !body.ends_with(' ') {
                    body.push(' ');
                }
            }
            let arms = &text[open..end];
            let catch_all = body
                .split([',', '\n', '{', '}'])
                .any(|arm| arm.trim_start().starts_with("_ =>"));
            if arms.contains("GiMethod::") && catch_all {
                out.push(text[..i].matches('\n').count() + 1);
            }
        }
        out
    }

    #[test]
    fn the_scan_finds_a_catch_all_over_methods() {
        let bad = "fn f(m: GiMethod) -> u32 {\n    match m {\n        GiMethod::Pathtrace => 2,\n        _ => 1,\n    }\n}\n";
        assert_eq!(catch_all_matches_over_methods(bad), vec![2]);
        let nested =
            "match m {\n    GiMethod::Vpl => match x { _ => 1 },\n    GiMethod::None => 0,\n}\n";
        assert!(catch_all_matches_over_methods(nested).is_empty());
        let other = "match (a, b) {\n    (true, Bounces::Fixed(_)) => {}\n    _ => {}\n}\n";
        assert!(catch_all_matches_over_methods(other).is_empty());
    }
}
