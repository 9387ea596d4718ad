//! One bounce: N rays per pixel in the voxel grid, the radiance at their hits from the
//! reflective light maps (Thiedemann 2010 §6.4.1) or from a direct-radiance volume
//! (`--gi-radiance volume`). Passes: `gi_hemisphere`, `gi_radiance_volume`.

use super::super::gi_hemisphere::GiHemisphere;
use super::super::gi_radiance_volume::GiRadianceVolume;
use super::super::{GiMethodPasses, GiSettings, GiTarget, RadianceSource};
use super::{rays_slider, temporal_controls, EmitterReach, LayerIndirect, MethodSpec};
use crate::vk::{Context, VkError};

pub(super) static SPEC: MethodSpec = MethodSpec {
    name: "hemisphere",
    description: "One bounce: N rays per pixel, radiance at hits from reflective light maps \
                  (Thiedemann 2010 §6.4.1)",
    summary: "one bounce",
    accumulates: false,
    temporal: true,
    needs_voxels: true,
    // The area lights' light maps are rendered for this method alone.
    reads_area_light_maps: true,
    // A ray that hits an emitting voxel reads the emission volume; a ray that leaves the grid reads
    // the environment.
    brings_emitters: EmitterReach::All,
    brings_environment: true,
    // The light maps do not see emitters: the hits read the emission volume.
    attribute_volumes: |s, scene| {
        s.radiance_source == RadianceSource::Volume || scene.has_emission()
    },
    // The direct-radiance volume's glossy voxels (their diffuse part and specular lobe).
    material_volume: |s| s.radiance_source == RadianceSource::Volume,
    // Layers trace the method's rays and read the hits as its pass does.
    transparent_indirect: |s| {
        Some(match s.radiance_source {
            RadianceSource::Volume => LayerIndirect::RadianceVolume,
            RadianceSource::Maps => LayerIndirect::LightMaps,
        })
    },
    history: |_, _, _| Vec::new(),
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
        "gi.radiance_source",
        "gi.temporal",
        "gi.temporal_frames",
    ],
    swept_by_default: true,
    plot_colour: "#1f77b4",
    describe: |gi| format!("hemisphere, {} rays, {}", gi.rays, super::filter_label(gi)),
    panel: |ui, gi, _| {
        rays_slider(ui, gi);
        temporal_controls(ui, gi);
    },
    build,
};

pub(super) fn build(
    ctx: &Context,
    settings: &GiSettings,
    target: &GiTarget<'_>,
) -> Result<Box<dyn GiMethodPasses>, VkError> {
    Ok(if settings.radiance_source == RadianceSource::Volume {
        Box::new(GiRadianceVolume::new(
            ctx,
            target,
            settings.emitter_sampling,
        )?)
    } else {
        Box::new(GiHemisphere::new(
            ctx,
            (target.has_phong, target.scene.has_ggx()),
            target.scene.has_emission(),
            crate::scene::Environment::shader_kind(target.scene.environment.as_ref()),
            target.temporal,
        )?)
    })
}
