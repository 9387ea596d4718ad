//! B bounces with albedo and normal from the voxel volumes and the direct light at every hit
//! from the shadow maps, accumulated over frames (Thiedemann 2010 §6.4.2). Pass:
//! `gi_pathtrace`.

use super::super::gi_pathtrace::GiPathtrace;
use super::{rays_slider, EmitterReach, LayerIndirect, MethodSpec};

pub(super) static SPEC: MethodSpec = MethodSpec {
    name: "pathtrace",
    description: "B bounces with albedo and normal from voxel volumes and direct light at \
                  every hit from the shadow maps, accumulated over frames (Thiedemann 2010 \
                  §6.4.2)",
    summary: "multi-bounce",
    accumulates: true,
    temporal: true,
    needs_voxels: true,
    reads_area_light_maps: false,
    // Next-event estimation toward the emissive triangles, MIS-weighted with the BSDF rays that hit
    // emitting voxels; rays that leave the grid read the environment.
    brings_emitters: EmitterReach::All,
    brings_environment: true,
    attribute_volumes: |_, _| true,
    // Later bounces sample the Phong and GGX lobes unless `--pathtrace-lobes false`.
    material_volume: |s| s.pathtrace_lobes,
    // Its paths from each transparent fragment, with its rays and bounces.
    transparent_indirect: |_| Some(LayerIndirect::Paths),
    // Per stereo eye: see `GiTarget::eyes` (the renderer repeats this list per eye).
    history: |s, size, _| match super::super::GiPasses::temporal_on(s) {
        true => vec![],
        false => vec![GiPathtrace::history_desc(size)],
    },
    filter_tile: |_| [1, 1],
    multiview_blocker: None,
    orthographic_blocker: None,
    sweep_keys: &[
        "gi.rays",
        "gi.radius_m",
        "gi.normal_offset_voxels",
        "gi.ray_offset_voxels",
        "gi.filter_radius",
        "gi.filter_passes",
        "gi.filter",
        "gi.start_level",
        "gi.max_iterations",
        "gi.light_map_resolution",
        "gi.bounces",
        "gi.accumulate_frames",
        "gi.temporal",
        "gi.temporal_frames",
    ],
    swept_by_default: true,
    plot_colour: "#d62728",
    describe: |gi| {
        format!(
            "pathtrace, {} rays, {} bounces, {}",
            gi.rays,
            gi.bounces,
            super::filter_label(gi)
        )
    },
    panel: |ui, gi, frames| {
        use crate::panel_keys::{key_slider, key_switch};
        use crate::scene::schema::Value;
        rays_slider(ui, gi);
        let unbounded = (Value::Word, Value::Count(2));
        key_switch(
            ui,
            gi,
            "gi.bounces",
            "unbounded (Russian roulette)",
            unbounded,
        );
        key_slider(ui, gi, "gi.bounces", (1.0, 8.0), false, "bounces");
        super::temporal_controls(ui, gi);
        match frames {
            Some(n) => ui.label(format!("accumulated frames: {n}")),
            None => ui.label("accumulated frames: –"),
        };
    },
    build: |ctx, settings, target| {
        Ok(Box::new(GiPathtrace::new(
            ctx,
            target,
            settings.pathtrace_lobes,
            settings.emitter_sampling,
            settings.env_sampling,
            super::super::GiPasses::temporal_on(settings),
        )?))
    },
};
