//! Virtual point lights from the reflective light maps, B bounces, interleaved sampling with
//! voxel visibility and the geometry-aware filter (Thiedemann 2010 Ch. 7). Passes: `vpl`,
//! `gi_vpl_emit`.

use super::super::vpl::VplPasses;
use super::super::GiSettings;
use super::MethodSpec;

pub(super) static SPEC: MethodSpec = MethodSpec {
    name: "vpl",
    description: "Virtual point lights from the reflective light maps, B bounces, interleaved \
                  sampling with voxel visibility and the geometry-aware filter (Thiedemann \
                  2010 Ch. 7)",
    summary: "virtual point lights",
    accumulates: false,
    needs_voxels: true,
    reads_area_light_maps: false,
    // Bounces after the first, and the emitters' rays, read albedo and normal at their voxel
    // hits.
    attribute_volumes: |s, scene| {
        s.vpl.bounces > 1
            || scene.has_emission()
            || scene.lights.iter().any(crate::scene::Light::is_area)
    },
    // Glossy hits of the bounces and the emitter rays.
    material_volume: |_| true,
    history: |_, _, _| Vec::new(),
    // Each pixel of an N×M tile shades one VPL set (interleaved sampling, §7.2).
    filter_tile: |s| s.vpl.pattern,
    multiview_blocker: None,
    orthographic_blocker: None,
    sweep_keys: &[
        "gi.normal_offset_voxels",
        "gi.ray_offset_voxels",
        "gi.filter_radius",
        "gi.filter_passes",
        "gi.start_level",
        "gi.max_iterations",
        "gi.light_map_resolution",
        "gi.vpls",
        "gi.vpl_pattern",
        "gi.vpl_d_min_voxels",
        "gi.vpl_bounces",
        "gi.vpl_visibility",
        "gi.vpl_normalize",
        "gi.vpl_spot_sampling",
        "gi.vpl_shading",
    ],
    swept_by_default: true,
    plot_colour: "#2ca02c",
    describe: |gi| {
        format!(
            "vpl, {} per set, {}×{} sets, {} bounces, filter {}×{}",
            gi.vpl.per_set,
            gi.vpl.pattern[0],
            gi.vpl.pattern[1],
            gi.vpl.bounces,
            gi.filter_radius,
            gi.filter_passes
        )
    },
    panel: |ui, gi, _| vpl_controls(ui, gi),
    build: |ctx, settings, target| Ok(Box::new(VplPasses::new(ctx, settings, target)?)),
};

/// The VPL method's parameters (Thiedemann 2010, Ch. 7): VPLs per set, pattern, bounces,
/// d_min, the glossy receivers' roughness floor, visibility, normalization, spot sampling.
fn vpl_controls(ui: &mut egui::Ui, gi: &mut GiSettings) {
    use crate::gi::vpl::{VplNormalize, VplShading, VplSpotSampling, VplVisibility};
    let v = &mut gi.vpl;
    ui.add(
        egui::Slider::new(&mut v.per_set, crate::scene::gi_range::VPLS.slider(1, 64))
            .logarithmic(true)
            .text("VPLs / set / light"),
    );
    for (side, name) in v.pattern.iter_mut().zip(["pattern N", "pattern M"]) {
        ui.add(
            egui::Slider::new(side, crate::scene::gi_range::VPL_PATTERN_SIDE.slider(1, 8))
                .text(name),
        );
    }
    ui.add(
        egui::Slider::new(
            &mut v.bounces,
            crate::scene::gi_range::VPL_BOUNCES.slider(1, 8),
        )
        .text("bounces"),
    );
    ui.add(
        egui::Slider::new(
            &mut v.d_min_voxels,
            crate::scene::gi_range::VPL_D_MIN.slider(0.0, 64.0),
        )
        .text("d_min (voxel diagonals)"),
    );
    ui.add(
        egui::Slider::new(
            &mut v.min_roughness,
            crate::scene::gi_range::VPL_MIN_ROUGHNESS.slider(0.0, 1.0),
        )
        .text("glossy receivers' min. roughness"),
    );
    let mut visible = v.visibility == VplVisibility::Voxel;
    ui.checkbox(&mut visible, "voxel visibility");
    v.visibility = if visible {
        VplVisibility::Voxel
    } else {
        VplVisibility::None
    };
    let mut valid = v.normalize == VplNormalize::Valid;
    ui.checkbox(&mut valid, "renormalize by valid VPLs");
    v.normalize = if valid {
        VplNormalize::Valid
    } else {
        VplNormalize::All
    };
    let mut disk = v.spot_sampling == VplSpotSampling::Disk;
    ui.checkbox(&mut disk, "spot VPLs in the image-plane disk");
    v.spot_sampling = if disk {
        VplSpotSampling::Disk
    } else {
        VplSpotSampling::SolidAngle
    };
    let mut splat = v.shading == VplShading::Splat;
    ui.checkbox(&mut splat, "splat (one pass per VPL)");
    v.shading = if splat {
        VplShading::Splat
    } else {
        VplShading::Gather
    };
    ui.checkbox(&mut v.show, "show VPLs");
}
