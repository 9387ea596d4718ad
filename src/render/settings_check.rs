//! The whole-settings checks of [`Renderer::new`](super::Renderer::new): every value against its
//! [`Limit`](crate::limits::Limit) (the ranges flags, scene files and the panel share), and the
//! image sizes against the device.

use super::RenderSettings;
use crate::limits::*;

/// Checks every value of `s` that has a [`Limit`], naming the flag of the first one out of
/// range. `Renderer::new` runs it, so values that reach the renderer by any path (flags,
/// scene files, the panel, the library) are checked the same way.
pub fn check_render_settings(s: &RenderSettings) -> Result<(), LimitError> {
    WIDTH.check_flag(s.width)?;
    HEIGHT.check_flag(s.height)?;
    TIME_S.check_flag(s.time_s)?;
    crate::scene::schema::check(&crate::scene::PostTable {
        post: s.post,
        tonemap: s.tonemap,
        dynres: Default::default(),
    })?;
    crate::scene::schema::check(&s.shadow)?;
    if let Some(v) = &s.voxels {
        VOXELS.check_flag(v.max_res_xy)?;
        VOXEL_LAYERS.check_flag(v.layers)?;
    }
    check_gi(&s.gi)?;
    OIT_NODES_PER_PIXEL.check_flag(s.oit_nodes_per_pixel)?;
    if let Some(d) = &s.debug {
        DEBUG_LEVEL.check_flag(d.level)?;
        DEBUG_STEPS_SCALE.check_flag(d.steps_scale)?;
    }
    Ok(())
}

/// Checks the image sizes of `s` against the device's `maxImageDimension2D`: the frame, shadow
/// maps and light maps are 2D images. Within `WIDTH` etc. on every driver voxgi has met,
/// but a device may offer less.
pub fn check_device_limits(
    s: &RenderSettings,
    max_image_dimension_2d: u32,
) -> Result<(), LimitError> {
    let sizes = [
        (&WIDTH, s.width),
        (&HEIGHT, s.height),
        (
            &crate::scene::shadow_range::SHADOW_RESOLUTION,
            s.shadow.resolution,
        ),
        (
            &crate::scene::gi_range::LIGHT_MAP_RESOLUTION,
            s.gi.light_map_resolution,
        ),
    ];
    for (limit, v) in sizes {
        if v > max_image_dimension_2d {
            return Err(LimitError {
                name: limit.flag.to_owned(),
                value: v.to_string(),
                expected: format!(
                    "{}, at most {max_image_dimension_2d} on this device (its largest image side)",
                    limit.what
                ),
            });
        }
    }
    Ok(())
}

/// Checks the indirect-light values against their keys' ranges (`GiSettings::keys`), naming
/// the flag.
pub fn check_gi(g: &crate::gi::GiSettings) -> Result<(), LimitError> {
    crate::scene::schema::check(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_sizes_beyond_the_device_name_their_flag() {
        let s = RenderSettings {
            width: 4097,
            ..Default::default()
        };
        let e = check_device_limits(&s, 4096).unwrap_err();
        assert_eq!(e.name, "--width");
        assert!(e.expected.contains("at most 4096 on this device"), "{e}");
        let mut s = RenderSettings::default();
        s.shadow.resolution = 8192;
        assert_eq!(
            check_device_limits(&s, 4096).unwrap_err().name,
            "--shadow-resolution"
        );
        let mut s = RenderSettings::default();
        s.gi.light_map_resolution = 8192;
        assert_eq!(
            check_device_limits(&s, 4096).unwrap_err().name,
            "--light-map-resolution"
        );
        check_device_limits(&RenderSettings::default(), 4096).expect("defaults fit 4096");
    }

    #[test]
    fn the_default_settings_are_in_range() {
        check_render_settings(&RenderSettings::default()).expect("defaults in range");
        let s = RenderSettings {
            voxels: Some(Default::default()),
            debug: Some(Default::default()),
            ..Default::default()
        };
        check_render_settings(&s).expect("defaults in range");
    }

    #[test]
    fn each_render_setting_out_of_range_names_its_flag() {
        type Edit = fn(&mut RenderSettings);
        let cases: [(&str, Edit); 19] = [
            ("--width", |s| s.width = 0),
            ("--height", |s| s.height = 20_000),
            ("--time", |s| s.time_s = f32::NAN),
            ("--exposure", |s| s.tonemap.exposure = f32::NAN),
            ("--shadow-resolution", |s| s.shadow.resolution = 0),
            ("--pcf-radius", |s| s.shadow.pcf_radius = 100),
            ("--voxels", |s| {
                s.voxels = Some(crate::voxel::gpu::VoxelSettings {
                    max_res_xy: 100_000,
                    ..Default::default()
                })
            }),
            ("--voxel-layers", |s| {
                s.voxels = Some(crate::voxel::gpu::VoxelSettings {
                    layers: 0,
                    ..Default::default()
                })
            }),
            ("--gi-rays", |s| s.gi.rays = 0),
            ("--gi-radius", |s| s.gi.radius_m = Some(f32::NAN)),
            ("--gi-normal-offset", |s| s.gi.normal_offset_voxels = -1.0),
            ("--gi-ray-offset", |s| {
                s.gi.ray_offset_voxels = f32::INFINITY
            }),
            ("--gi-filter-radius", |s| s.gi.filter_radius = 65),
            ("--gi-filter-passes", |s| s.gi.filter_passes = 17),
            ("--gi-frames", |s| s.gi.accumulate_frames = 0),
            ("--light-map-resolution", |s| s.gi.light_map_resolution = 8),
            ("--gi-start-level", |s| s.gi.start_level = 15),
            ("--gi-max-iterations", |s| s.gi.max_iterations = 0),
            ("--vpl-min-roughness", |s| s.gi.vpl.min_roughness = 1.5),
        ];
        for (flag, edit) in cases {
            let mut s = RenderSettings::default();
            edit(&mut s);
            let e = check_render_settings(&s).expect_err(flag);
            assert_eq!(e.name, flag, "{e}");
        }
        let mut s = RenderSettings {
            debug: Some(Default::default()),
            ..Default::default()
        };
        s.debug.as_mut().unwrap().level = 15;
        assert_eq!(check_render_settings(&s).unwrap_err().name, "--debug-level");
        s.debug.as_mut().unwrap().level = 0;
        s.debug.as_mut().unwrap().steps_scale = 0;
        assert_eq!(
            check_render_settings(&s).unwrap_err().name,
            "--debug-steps-scale"
        );
    }
}
