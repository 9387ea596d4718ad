//! `voxgi render`: one headless frame to PNG (and EXR), optionally compared with a reference.

use super::args::FrameArgs;
use super::{outln, with_context, CliError, Global};
use crate::render::{render_image, render_stereo, StereoSettings};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `voxgi render`.
#[derive(clap::Args, Clone)]
pub struct RenderArgs {
    /// A built-in scene (cornell, cornell-point), a TOML scene file, or a glTF (.gltf/.glb) or
    /// OBJ model alone (framed by a camera, lit by a default sun without lights). Default:
    /// cornell.
    pub scene: Option<String>,
    /// Output PNG (tone-mapped, sRGB; the name must end in .png — `--exr` writes the HDR).
    #[arg(short, long, default_value = "voxgi.png")]
    pub output: PathBuf,
    /// Also write the linear HDR radiance (W/(m² sr)) as OpenEXR.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Compare the linear radiance with a reference EXR and print the metrics.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    #[command(flatten)]
    pub stereo: StereoArgs,
}

/// Prints the eyes' parallax and what the second eye and the packing cost on the GPU.
/// `chosen`: why the path was chosen where --stereo-path was not given.
fn print_stereo(
    stereo: &StereoSettings,
    chosen: Option<&str>,
    s: &crate::render::StereoOutput,
    out: &mut dyn Write,
) -> Result<(), CliError> {
    let total = |t: &[crate::vk::PassTiming]| t.iter().map(|t| t.gpu_ms).sum::<f64>();
    let mode = stereo.mode.name();
    let path = stereo_path_line(stereo.path, chosen, s.path, s.fallback.as_deref());
    let (e, c) = (stereo.rig.separation_m, stereo.rig.convergence_m);
    let eyes = match s.path {
        crate::render::StereoPath::OneFrame | crate::render::StereoPath::Multiview => {
            format!("both eyes in one frame {:.3}", total(&s.left.timings))
        }
        crate::render::StereoPath::TwoPass => format!(
            "left eye {:.3}, right eye {:.3}",
            total(&s.left.timings),
            total(&s.right.timings)
        ),
    };
    outln!(
        out,
        "stereo {mode}, path {path}: eye separation {e} m, convergence {c} m; GPU ms {eyes}, packing {:.3}",
        total(&s.pack_timings)
    );
    Ok(())
}

/// The path that ran (`ran`), with why where it was the default (`chosen`) and why it is
/// not the one asked for (`fallback`).
pub fn stereo_path_line(
    asked: crate::render::StereoPath,
    chosen: Option<&str>,
    ran: crate::render::StereoPath,
    fallback: Option<&str>,
) -> String {
    let chosen = chosen.map(|why| format!(" ({why})")).unwrap_or_default();
    match fallback {
        Some(why) => format!("two-pass ({}{chosen} falls back: {why})", asked.name()),
        None => format!("{}{chosen}", ran.name()),
    }
}

/// Stereo flags of `voxgi render`.
#[derive(clap::Args, Clone)]
pub struct StereoArgs {
    /// Render both eyes (off-axis parallel frusta) and pack them into one image: an anaglyph
    /// (left eye red) or a spatial packing. `render`: into --output, side-by-side-full twice
    /// --width wide, --exr and --compare then take the left eye; `view`: into the window.
    #[arg(long, value_enum, value_name = "MODE")]
    pub stereo: Option<crate::post::StereoMode>,
    /// Distance between the eyes in meters (with --stereo).
    #[arg(long, value_name = "M", default_value_t = crate::scene::StereoRig::default().separation_m)]
    pub eye_separation: f32,
    /// Distance of the zero-parallax plane in meters along the view direction (with --stereo);
    /// default: the distance to the centre of the scene's bounding box.
    #[arg(long, value_name = "M")]
    pub convergence: Option<f32>,
    /// How the eyes are rendered (with --stereo): one-frame renders both eyes in one frame
    /// with world-space work (shadow maps, voxels, light maps, VPLs) once, the G-buffer drawn
    /// per eye; multiview draws both eyes' G-buffer in one Vulkan multiview pass instead;
    /// two-pass renders the whole frame per eye. One-frame and multiview fall back to
    /// two-pass where they cannot run, and say why. Default (`render`, `profile`): multiview
    /// where the device has the Vulkan feature, else one-frame; the viewer starts on
    /// one-frame.
    #[arg(long, value_enum, value_name = "PATH")]
    pub stereo_path: Option<crate::render::StereoPath>,
}

impl StereoArgs {
    /// The stereo settings, `None` without --stereo; a value out of its range is an error
    /// naming its flag.
    pub fn settings(
        &self,
        scene: &crate::scene::Scene,
        time_s: f32,
    ) -> Result<Option<StereoSettings>, CliError> {
        let Some(mode) = self.stereo else {
            return Ok(None);
        };
        Ok(Some(StereoSettings {
            mode,
            rig: self.rig(scene, time_s)?,
            path: self.stereo_path.unwrap_or_default(),
        }))
    }

    /// Takes the device's default path ([`crate::render::default_stereo_path`]) into
    /// `stereo` where --stereo-path was not given, and returns why it was chosen.
    pub fn take_default_path(
        &self,
        info: &crate::vk::DeviceInfo,
        stereo: &mut StereoSettings,
    ) -> Option<String> {
        if self.stereo_path.is_some() {
            return None;
        }
        let (path, why) = crate::render::default_stereo_path(info);
        stereo.path = path;
        Some(why)
    }

    /// The eyes' parallax: --eye-separation and --convergence (default: the depth of the
    /// scene box's centre), each checked against its limit.
    pub fn rig(
        &self,
        scene: &crate::scene::Scene,
        time_s: f32,
    ) -> Result<crate::scene::StereoRig, CliError> {
        let convergence_m = self
            .convergence
            .unwrap_or_else(|| crate::render::default_convergence_m(scene, time_s));
        Ok(crate::scene::StereoRig {
            separation_m: crate::limits::STEREO_SEPARATION_M.check_flag(self.eye_separation)?,
            convergence_m: crate::limits::STEREO_CONVERGENCE_M.check_flag(convergence_m)?,
        })
    }
}

/// Renders, writes the images and prints the pass times (and the metrics with `--compare`).
/// With `--stereo` the PNG is the packed pair and the EXR, metrics and debug description are
/// the left eye's.
pub fn render(global: &Global, args: &RenderArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let png = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !png {
        return Err(CliError::OutputNotPng {
            path: args.output.clone(),
        });
    }
    let frame = &args.frame;
    let scene = frame.camera.load_scene(args.scene.as_deref())?;
    let settings = frame.settings(&scene)?;
    let stereo = args.stereo.settings(&scene, settings.time_s)?;
    with_context(global, |ctx| {
        let (image, packed, packed_size) = match stereo {
            None => {
                let mut image = render_image(ctx, &scene, &settings)?;
                let ldr = std::mem::take(&mut image.ldr);
                (image, ldr, (frame.width, frame.height))
            }
            Some(mut stereo) => {
                let chosen = args.stereo.take_default_path(&ctx.info, &mut stereo);
                let s = render_stereo(ctx, &scene, &settings, stereo)?;
                print_stereo(&stereo, chosen.as_deref(), &s, out)?;
                (s.left, s.packed, s.packed_size)
            }
        };
        image::save_buffer(
            &args.output,
            &packed,
            packed_size.0,
            packed_size.1,
            image::ColorType::Rgba8,
        )
        .map_err(|source| CliError::WriteImage {
            path: args.output.clone(),
            source,
        })?;
        outln!(out, "wrote {}", args.output.display());
        if let Some(path) = &args.exr {
            image.hdr.save_exr(path)?;
            outln!(out, "wrote {}", path.display());
        }
        for t in &image.timings {
            outln!(out, "  {:<16} {:>9.3} ms", t.name, t.gpu_ms);
        }
        if let Some(a) = image.auto_shadow {
            eprintln!(
                "shadow maps: --shadow-resolution auto picked {r}² (95% of the lit pixels' shadow \
                 texels at most 1 px: their 95th percentile was {q:.3} px at the {p}² probe, so \
                 {scaled:.3} px at {r}²)",
                r = a.resolution,
                q = a.quantile_px_at_probe,
                p = a.probe_resolution,
                scaled = a.quantile_px_at_probe * a.probe_resolution as f32 / a.resolution as f32
            );
        }
        if let Some(d) = &image.debug_description {
            outln!(out, "{d}");
        }
        if let Some(warning) = image.oit.and_then(|s| s.overflow_warning()) {
            log::warn!("transparency: {warning}");
        }
        if let Some(reference) = &args.compare {
            let r = crate::eval::HdrImage::load(reference)?;
            let m = crate::eval::compare(&r, &image.hdr, None)?;
            super::compare::print_metrics(&m, out)?;
        }
        Ok(())
    })
}
