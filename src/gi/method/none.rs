//! No indirect light: the frame is the direct light alone.

use super::{EmitterReach, MethodSpec};

pub(super) static SPEC: MethodSpec = MethodSpec {
    name: "none",
    description: "No indirect light",
    summary: "direct light only",
    accumulates: false,
    temporal: false,
    needs_voxels: false,
    reads_area_light_maps: false,
    // No indirect light, so nothing reaches a surface but the direct light.
    brings_emitters: EmitterReach::Nothing,
    brings_environment: false,
    attribute_volumes: |_, _| false,
    material_volume: |_| false,
    transparent_indirect: |_| None,
    history: |_, _, _| Vec::new(),
    filter_tile: |_| [1, 1],
    multiview_blocker: None,
    orthographic_blocker: None,
    sweep_keys: &[],
    swept_by_default: true,
    plot_colour: "#7f7f7f",
    describe: |_| "none".into(),
    panel: |ui, _, _| {
        ui.label("direct light only");
    },
    // The renderer builds no GI passes without indirect light; should anything ask, the
    // hemisphere's passes are the cheapest that fill the indirect image.
    build: super::hemisphere::build,
};
