//! The flags shared by several commands, and their conversion into the renderer's settings.

use crate::gi::GiMethod;
use crate::light::PointShadow;
use crate::post::ToneOperator;
use crate::render::RenderSettings;
use crate::scene::{resolve_gi, GiOverrides, Scene};

/// Indirect-light flags of `render`, `profile`, `graph` and `view`. Each one given overrides the
/// scene file's `[gi]` value, which overrides the default shown.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct GiArgs {
    /// Indirect-light method (none: direct light only) [default: the scene's `[gi] method`,
    /// else none].
    #[arg(long, value_enum)]
    pub gi: Option<GiMethod>,
    /// Where hemisphere sampling reads the radiance at ray hits: reflective light maps or a
    /// direct-radiance voxel volume.
    #[arg(long, value_enum, default_value_t = crate::gi::RadianceSource::Maps)]
    pub gi_radiance: crate::gi::RadianceSource,
    /// Hierarchy level GI rays start their traversal at (Thiedemann 2010, §5.3.2).
    #[arg(long, default_value_t = 1)]
    pub gi_start_level: u32,
    /// Iteration cap of GI rays' hierarchical traversal (too low shows as missing indirect
    /// shadows, thesis Fig. 46).
    #[arg(long, default_value_t = 1024)]
    pub gi_max_iterations: u32,
    /// GI rays per pixel [default: the scene's `[gi] rays`, else 16].
    #[arg(long, value_name = "N")]
    pub gi_rays: Option<u32>,
    /// GI ray length in meters [default: the scene's `[gi] radius_m`, else the scene's
    /// diagonal].
    #[arg(long, value_name = "M")]
    pub gi_radius: Option<f32>,
    /// Self-intersection offset along the normal, in voxel diagonals (thesis k1) [default: the
    /// scene's `[gi] normal_offset_voxels`, else 1].
    #[arg(long, value_name = "K1")]
    pub gi_normal_offset: Option<f32>,
    /// Self-intersection offset along the ray, in voxel diagonals over cos (thesis k2)
    /// [default: the scene's `[gi] ray_offset_voxels`, else 0].
    #[arg(long, value_name = "K2")]
    pub gi_ray_offset: Option<f32>,
    /// Geometry-aware filter radius in pixels, 0: off [default: the scene's `[gi]
    /// filter_radius`, else 4].
    #[arg(long, value_name = "R")]
    pub gi_filter_radius: Option<u32>,
    /// Geometry-aware filter passes, each horizontal + vertical [default: the scene's `[gi]
    /// filter_passes`, else 2].
    #[arg(long, value_name = "P")]
    pub gi_filter_passes: Option<u32>,
    /// Path-tracer bounces, 1..=64, or `unbounded`: 3 bounces, then Russian roulette ends each
    /// path (unbiased; capped at 64) [default: the scene's `[gi] bounces`, else 2].
    #[arg(long, value_name = "B")]
    pub gi_bounces: Option<crate::gi::Bounces>,
    /// Frames the path tracer accumulates in a headless render [default: the scene's `[gi]
    /// accumulate_frames`, else 1].
    #[arg(long, value_name = "F")]
    pub gi_frames: Option<u32>,
    /// Reflective light-map resolution per light view [default: the scene's `[gi]
    /// light_map_resolution`, else 256].
    #[arg(long, value_name = "L")]
    pub light_map_resolution: Option<u32>,
    /// `--gi vpl`: VPLs per interleaving set and light (thesis §7.2) [default: the scene's
    /// `[gi] vpls`, else 16].
    #[arg(long, value_name = "K")]
    pub vpls: Option<u32>,
    /// `--gi vpl`: interleaved-sampling pattern NxM, N·M VPL sets (thesis §7.3.2) [default:
    /// the scene's `[gi] vpl_pattern`, else 4x4].
    #[arg(long, value_name = "NxM", value_parser = crate::gi::vpl::parse_pattern)]
    pub vpl_pattern: Option<[u32; 2]>,
    /// `--gi vpl`: d_min of E = I cos cos / (d_min + d²) (thesis §7.3) as a distance in voxel
    /// diagonals h: d_min = (D · h)² [default: the scene's `[gi] vpl_d_min_voxels`, else 8].
    #[arg(long, value_name = "D")]
    pub vpl_d_min: Option<f32>,
    /// `--gi vpl`: the roughness floor of glossy receivers, in [0, 1]: GGX pixels are shaded
    /// with roughness max(r, R) toward the VPLs, Phong exponents capped at 2/R⁴ − 2; bounds a
    /// sharp lobe's highlights of single VPLs, blurs smoother receivers [default: the scene's
    /// `[gi] vpl_min_roughness`, else 0.4].
    #[arg(long, value_name = "R")]
    pub vpl_min_roughness: Option<f32>,
    /// `--gi vpl`: VPL bounces: 1 reflects the lights' direct light once, 2 adds one voxel
    /// ray per VPL (thesis §7.2), up to 8 [default: the scene's `[gi] vpl_bounces`, else 2].
    #[arg(long, value_name = "B")]
    pub vpl_bounces: Option<u32>,
    /// `--gi vpl`: visibility per VPL and pixel: the voxel segment test, or none (v = 1)
    /// [default: the scene's `[gi] vpl_visibility`, else voxel].
    #[arg(long, value_enum)]
    pub vpl_visibility: Option<crate::gi::vpl::VplVisibility>,
    /// `--gi vpl`: divide a light's flux among all K samples of its emission domain
    /// (unbiased: light that hits nothing leaves the scene) or among the valid ones only (the
    /// thesis's renormalization) [default: the scene's `[gi] vpl_normalize`, else all].
    #[arg(long, value_enum)]
    pub vpl_normalize: Option<crate::gi::vpl::VplNormalize>,
    /// `--gi vpl`: spot VPL directions uniform in solid angle on the cone, or uniform in the
    /// disk of the spot's image plane (thesis §7.2), weighted by their solid angle [default:
    /// the scene's `[gi] vpl_spot_sampling`, else solid-angle].
    #[arg(long, value_enum)]
    pub vpl_spot_sampling: Option<crate::gi::vpl::VplSpotSampling>,
    /// `--gi vpl`: shade by one gather loop per pixel, or by one additive pass per VPL
    /// (the thesis's splatting).
    #[arg(long, value_enum, default_value_t = crate::gi::vpl::VplShading::Gather)]
    pub vpl_shading: crate::gi::vpl::VplShading,
    /// `--gi vpl`: debug view, every VPL drawn as a dot over the image (first bounce yellow,
    /// later ones cyan).
    #[arg(long)]
    pub vpl_show: bool,
    /// `--gi ssgi`: the internal GI resolution, the frame's divided by 1, 2, 4 or 8 [default:
    /// the scene's `[gi] ssgi_resolution`, else half].
    #[arg(long, value_enum)]
    pub ssgi_resolution: Option<crate::gi::SsgiResolution>,
    /// `--gi ssgi`: samples per texel and pyramid level [default: the scene's `[gi]
    /// ssgi_samples`, else 64].
    #[arg(long, value_name = "N")]
    pub ssgi_samples: Option<u32>,
    /// `--gi ssgi`: how depth and normal mips pick a texel: the voting filter or the nearest
    /// child (fast) [default: the scene's `[gi] ssgi_mips`, else voting].
    #[arg(long, value_enum)]
    pub ssgi_mips: Option<crate::gi::SsgiMips>,
    /// `--gi ssgi`: no feedback of the previous frame's indirect light (one bounce only)
    /// [default: the scene's `[gi] ssgi_feedback`, else feedback on].
    #[arg(long)]
    pub ssgi_no_feedback: bool,
    /// `--gi ssgi`: clamp of the fed-back irradiance in W/m² [default: the scene's `[gi]
    /// ssgi_feedback_max_w_m2`, else 20].
    #[arg(long, value_name = "E")]
    pub ssgi_feedback_max: Option<f32>,
    /// `--gi ssgi`: τ of the temporal blend with the reprojected history, 0 (off) to 0.99
    /// [default: the scene's `[gi] ssgi_history_weight`, else 0.9].
    #[arg(long, value_name = "TAU")]
    pub ssgi_history_weight: Option<f32>,
    /// `--gi ssgi`: screen-space reflection rays on Phong and GGX materials (on), or only the
    /// diffuse fallback (off) [default: the scene's `[gi] ssr`, else on].
    #[arg(long, value_enum)]
    pub ssr: Option<crate::gi::SsrMode>,
    /// `--gi ssgi`: reflection rays along the mirror direction, the lobe's width read as a
    /// coarser colour mip (mirror), or one lobe sample per pixel and frame averaged by the
    /// history (lobe) [default: the scene's `[gi] ssr_rays`, else mirror].
    #[arg(long, value_enum)]
    pub ssr_rays: Option<crate::gi::SsrRays>,
    /// Modified SAO (Oetke 2017 §2.5) at half resolution, multiplied into the indirect light
    /// (needs a --gi method: direct light is not darkened); `--sao off` turns off the scene's
    /// [default: the scene's `[gi] sao`, else off].
    #[arg(long, value_enum, value_name = "on|off", num_args = 0..=1, default_missing_value = "on")]
    pub sao: Option<Toggle>,
    /// SAO: sample radius r in meters [default: the scene's `[gi] sao_radius_m`, else 1.8].
    #[arg(long, value_name = "M")]
    pub sao_radius: Option<f32>,
    /// SAO: bias β in meters of v·n [default: the scene's `[gi] sao_bias`, else 0.04].
    #[arg(long, value_name = "M")]
    pub sao_bias: Option<f32>,
    /// SAO: contrast k, the AO term's exponent [default: the scene's `[gi] sao_contrast`,
    /// else 2].
    #[arg(long, value_name = "K")]
    pub sao_contrast: Option<f32>,
    /// SAO: ε of v·v + ε in m² [default: the scene's `[gi] sao_epsilon_m2`, else 0.01].
    #[arg(long, value_name = "M2")]
    pub sao_epsilon: Option<f32>,
    /// SAO debug view: the AO term as grey (1 white = unoccluded) instead of the image (needs
    /// SAO on, by --sao or the scene).
    #[arg(long)]
    pub sao_show: bool,
}

impl GiArgs {
    /// The flags given, for [`crate::scene::resolve_gi`].
    pub fn overrides(&self) -> GiOverrides {
        GiOverrides {
            method: self.gi,
            rays: self.gi_rays,
            bounces: self.gi_bounces,
            radius_m: self.gi_radius,
            normal_offset_voxels: self.gi_normal_offset,
            ray_offset_voxels: self.gi_ray_offset,
            filter_radius: self.gi_filter_radius,
            filter_passes: self.gi_filter_passes,
            light_map_resolution: self.light_map_resolution,
            accumulate_frames: self.gi_frames,
            vpl: crate::gi::vpl::VplOverrides {
                per_set: self.vpls,
                pattern: self.vpl_pattern,
                bounces: self.vpl_bounces,
                d_min_voxels: self.vpl_d_min,
                min_roughness: self.vpl_min_roughness,
                visibility: self.vpl_visibility,
                normalize: self.vpl_normalize,
                spot_sampling: self.vpl_spot_sampling,
            },
            ssgi: crate::scene::SsgiOverrides {
                resolution: self.ssgi_resolution,
                samples: self.ssgi_samples,
                mips: self.ssgi_mips,
                feedback: self.ssgi_no_feedback.then_some(false),
                feedback_max_w_m2: self.ssgi_feedback_max,
                history_weight: self.ssgi_history_weight,
                ssr: self.ssr.map(|m| m == crate::gi::SsrMode::On),
                ssr_rays: self.ssr_rays,
            },
            sao: crate::scene::SaoOverrides {
                enabled: self.sao.map(Toggle::on),
                radius_m: self.sao_radius,
                bias: self.sao_bias,
                contrast: self.sao_contrast,
                epsilon_m2: self.sao_epsilon,
            },
        }
    }

    /// SAO's value flags and `--sao-show` need SAO on (by `--sao` or the scene's `[gi] sao`):
    /// given while it is off they would do nothing, which is an error naming them.
    pub fn check_sao(&self, s: &crate::gi::GiSettings) -> Result<(), super::CliError> {
        let o = self.overrides().sao;
        if s.sao.is_none() && (o.has_values() || self.sao_show) {
            return Err(super::CliError::SaoOff);
        }
        Ok(())
    }

    /// The scene's `[gi]` values, overridden by the flags given.
    pub fn settings(&self, scene: &Scene) -> crate::gi::GiSettings {
        let s = crate::gi::GiSettings {
            radiance_source: self.gi_radiance,
            start_level: self.gi_start_level,
            max_iterations: self.gi_max_iterations,
            ..resolve_gi(&scene.gi, &self.overrides())
        };
        crate::gi::GiSettings {
            vpl: crate::gi::vpl::VplSettings {
                shading: self.vpl_shading,
                show: self.vpl_show,
                ..s.vpl
            },
            sao: s.sao.map(|a| crate::gi::SaoSettings {
                view: self.sao_show,
                ..a
            }),
            ..s
        }
    }
}

/// The camera's projection, over the scene's `[camera]` table (`render`, `profile`, `graph`,
/// `view`).
#[derive(clap::Args, Clone, Default)]
pub struct CameraArgs {
    /// The camera's projection; default: the scene's `[camera] projection`, else perspective.
    #[arg(long, value_enum)]
    pub projection: Option<crate::scene::Projection>,
    /// Height of the orthographic view in meters (its width follows the image's aspect);
    /// default: the scene's `[camera] ortho_height_m`, else the perspective view's height at
    /// the depth of the scene's centre.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub ortho_height: Option<f32>,
}

impl CameraArgs {
    /// Sets `scene`'s camera from the flags; a height out of range is an error naming
    /// `--ortho-height`.
    pub fn apply(&self, scene: &mut Scene) -> Result<(), super::CliError> {
        if let Some(h) = self.ortho_height {
            scene.camera.ortho_height_m = crate::limits::ORTHO_HEIGHT_M.check_flag(h)?;
        }
        if let Some(p) = self.projection {
            scene.camera.projection = p;
        }
        Ok(())
    }

    /// The scene `arg` names (see [`crate::scene::load_scene_arg`]) with the flags applied.
    pub fn load_scene(&self, arg: Option<&str>) -> Result<Scene, super::CliError> {
        let mut scene = crate::scene::load_scene_arg(arg)?;
        self.apply(&mut scene)?;
        Ok(scene)
    }
}

/// Frame settings shared by `render` and `profile`.
#[derive(clap::Args, Clone)]
pub struct FrameArgs {
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    /// Scene time in seconds (animations).
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// Tone-mapping operator [default: the scene's `[post] tonemap`, else filmic].
    #[arg(long, value_enum)]
    pub tonemap: Option<ToneOperator>,
    /// Exposure factor before tone mapping [default: the scene's `[post] exposure`, else 1].
    #[arg(long, value_name = "E")]
    pub exposure: Option<f32>,
    /// Shadow-map resolution: texels per side, or `auto`: the smallest power of two that keeps
    /// the shadow texel under a pixel on 95% of the lit pixels of the view (picked from one
    /// probe frame of `--debug shadow-texels` when the renderer is made).
    #[arg(long, default_value = "1024", value_name = "TEXELS|auto")]
    pub shadow_resolution: ShadowResolutionArg,
    /// PCF radius in texels.
    #[arg(long, default_value_t = 1)]
    pub pcf_radius: u32,
    /// Shadow cascades per directional light for the camera's direct light (1: one map for
    /// the whole scene); default: the scene's `[shadow] cascades`, else 4.
    #[arg(long, value_name = "N")]
    pub shadow_cascades: Option<u32>,
    /// Cascade splits: blend of logarithmic (1) and uniform (0) splits (Zhang et al. 2006);
    /// default: the scene's `[shadow] cascade_lambda`, else 0.5.
    #[arg(long, value_name = "LAMBDA")]
    pub shadow_cascade_lambda: Option<f32>,
    /// Shadow maps of point lights: six cube faces or two paraboloid hemispheres.
    #[arg(long, value_enum, default_value_t = PointShadow::Cube)]
    pub point_shadows: PointShadow,
    /// Sub-lights (one shadow view each) per sphere or rectangle light, for every area light;
    /// default: each light's `samples` key (16 without it).
    #[arg(long, value_name = "S")]
    pub area_samples: Option<u32>,
    /// Soft shadows of area lights: S sampled sub-lights (converges) or PCSS for rectangles
    /// (one shadow view each; spheres stay sampled).
    #[arg(long, value_enum, default_value_t = crate::light::AreaShadow::Sampled)]
    pub area_shadows: crate::light::AreaShadow,
    /// Surfaces with MTL d < 1 in the camera view: per-pixel linked lists sorted and blended
    /// (oit), or hashed alpha testing (hashed); default: the scene's `transparency` key, else
    /// oit. Shadow and light maps always use hashed alpha.
    #[arg(long, value_enum)]
    pub transparency: Option<crate::scene::Transparency>,
    /// Capacity of the transparency node buffer in layers per pixel on average (more
    /// fragments are dropped and reported).
    #[arg(long, value_name = "N", default_value_t = crate::render::OIT_DEFAULT_NODES_PER_PIXEL)]
    pub oit_nodes_per_pixel: u32,
    /// Voxelize the scene into a grid of at most N×N columns: static geometry once, dynamic
    /// objects in the frames they move (`profile` then shows those voxel passes).
    #[arg(long, value_name = "N")]
    pub voxels: Option<u32>,
    /// Depth layers of 128 voxels of the voxel grid.
    #[arg(long, default_value_t = 1)]
    pub voxel_layers: u32,
    /// Re-voxelize static geometry every frame too (measures the full voxelization).
    #[arg(long)]
    pub revoxelize: bool,
    /// Voxelizer: exact triangle/box test, or the thesis's texture-atlas splatting with
    /// automatic atlases (applies to --voxels, GI and --debug voxel grids).
    #[arg(long, value_enum, default_value_t = crate::voxel::gpu::Voxelizer::Triangle)]
    pub voxelizer: crate::voxel::gpu::Voxelizer,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub gi: GiArgs,
    #[command(flatten)]
    pub post: PostArgs,
    /// Show a debug view instead of the lit image: the voxel views (voxels, steps, level,
    /// albedo) voxelize at 128 unless --voxels; atlas shows an object's atlas; gbuffer-albedo,
    /// gbuffer-normal and gbuffer-distance show a G-buffer channel; shadow-texels the
    /// predicted on-screen size of the shadow-map texels (shadow aliasing),
    /// shadow-texels-perspective its perspective part (without cos α_i / cos α_s).
    #[arg(long, value_enum)]
    pub debug: Option<crate::voxel::debug_view::DebugView>,
    /// Hierarchy level shown by --debug level (0 = the voxels).
    #[arg(long, default_value_t = 0)]
    pub debug_level: u32,
    /// Traversal steps shown white by --debug steps.
    #[arg(long, default_value_t = 64)]
    pub debug_steps_scale: u32,
    /// The object whose atlas --debug atlas shows: its name or index in the scene.
    #[arg(long, default_value = "0")]
    pub object: String,
}

impl FrameArgs {
    /// The frame's settings; GI values not given as flags come from the scene's `[gi]`. A
    /// value out of its range ([`crate::limits`]) is an error naming its flag, before any
    /// GPU work.
    pub fn settings(&self, scene: &Scene) -> Result<RenderSettings, super::CliError> {
        let mut s = RenderSettings {
            width: self.width,
            height: self.height,
            time_s: self.time,
            ..Default::default()
        };
        let post = crate::scene::PostOverrides {
            tonemap: self.tonemap,
            exposure: self.exposure,
            ..self.post.overrides()
        };
        (s.post, s.tonemap) = crate::post::apply_overrides(&post.or(scene.post), s.post, s.tonemap);
        match self.shadow_resolution {
            ShadowResolutionArg::Texels(n) => s.shadow.resolution = n,
            ShadowResolutionArg::Auto => {
                s.shadow.resolution = crate::render::shadow_texels::AUTO_PROBE_RESOLUTION;
                s.shadow.auto_resolution = true;
            }
        }
        s.shadow.pcf_radius = self.pcf_radius;
        s.shadow.point_technique = self.point_shadows;
        s.shadow.area_technique = self.area_shadows;
        s.transparency = self.transparency.or(scene.transparency).unwrap_or_default();
        s.oit_nodes_per_pixel =
            crate::limits::OIT_NODES_PER_PIXEL.check_flag(self.oit_nodes_per_pixel)?;
        if let Some(n) = self.shadow_cascades.or(scene.shadow.cascades) {
            s.shadow.cascades = crate::limits::SHADOW_CASCADES.check_flag(n)?;
        }
        if let Some(l) = self.shadow_cascade_lambda.or(scene.shadow.cascade_lambda) {
            s.shadow.cascade_lambda = crate::limits::SHADOW_CASCADE_LAMBDA.check_flag(l)?;
        }
        if let Some(n) = self.area_samples {
            s.shadow.area_samples = Some(crate::limits::AREA_SAMPLES.check_flag(n)?);
        }
        let default_res = crate::voxel::gpu::VoxelSettings::default().max_res_xy;
        s.gi = self.gi.settings(scene);
        // GI and the voxel debug views voxelize without --voxels, honouring --voxelizer,
        // --voxel-layers and --revoxelize (the atlas and G-buffer views draw no voxels).
        let needs_voxels =
            s.gi.method != GiMethod::None || self.debug.is_some_and(|d| d.shows_voxels());
        s.voxels = self
            .voxels
            .or(needs_voxels.then_some(default_res))
            .map(|max_res_xy| crate::voxel::gpu::VoxelSettings {
                max_res_xy,
                layers: self.voxel_layers,
                revoxelize_static: self.revoxelize,
                voxelizer: self.voxelizer,
            });
        let object = match self.debug {
            Some(crate::voxel::debug_view::DebugView::Atlas) => scene.find_object(&self.object)?,
            _ => 0,
        };
        s.debug = self
            .debug
            .map(|view| crate::voxel::debug_view::DebugSettings {
                view,
                level: self.debug_level,
                steps_scale: self.debug_steps_scale,
                object,
                ..Default::default()
            });
        self.gi.check_sao(&s.gi)?;
        crate::render::check_render_settings(&s)?;
        Ok(s)
    }
}

/// `--taa`, `--fxaa`, `--dither`, `--sao`: given alone the stage is on; `off` turns off what
/// the scene file's table turns on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Toggle {
    On,
    Off,
}

impl Toggle {
    fn on(self) -> bool {
        self == Toggle::On
    }
}

/// `--auto-exposure [KEY|off]`: on (with the scene's or the default key), on with KEY, or off.
fn parse_key_or_off(s: &str) -> Result<crate::scene::Stage, String> {
    use crate::scene::Stage;
    match s {
        "on" => Ok(Stage::On(None)),
        "off" => Ok(Stage::Off),
        v => v
            .parse::<f32>()
            .map(|k| Stage::On(Some(k)))
            .map_err(|_| format!("`{v}`: expected a key value (e.g. 0.18) or `off`")),
    }
}

/// `--bloom STRENGTH|off`.
fn parse_strength_or_off(s: &str) -> Result<crate::scene::Stage, String> {
    use crate::scene::Stage;
    match s {
        "off" => Ok(Stage::Off),
        v => v
            .parse::<f32>()
            .map(|k| Stage::On(Some(k)))
            .map_err(|_| format!("`{v}`: expected a strength in [0, 1] (e.g. 0.05) or `off`")),
    }
}

/// Post-processing flags (all off by default). Each one given overrides the scene file's
/// `[post]` value, which overrides the default.
#[derive(clap::Args, Clone)]
pub struct PostArgs {
    /// Temporal anti-aliasing: Halton(2,3) sub-pixel jitter, reprojected and clipped history
    /// (a headless render runs --taa-frames frames); `--taa off` turns off the scene's
    /// [default: the scene's `[post] taa`, else off].
    #[arg(long, value_enum, value_name = "on|off", num_args = 0..=1, default_missing_value = "on")]
    pub taa: Option<Toggle>,
    /// TAA history weight α: each frame keeps α of the reprojected history [default: the
    /// scene's `[post] taa_history_weight`, else 0.9].
    #[arg(long, value_name = "ALPHA")]
    pub taa_history_weight: Option<f32>,
    /// Frames a headless render with TAA runs; the viewer blends one per frame and has no
    /// count [default: the scene's `[post] taa_frames`, else 16].
    #[arg(long, value_name = "N")]
    pub taa_frames: Option<u32>,
    /// Auto exposure: exposure = KEY / log-average luminance (KEY 0.18 when left out), adapted
    /// over frames; --exposure then multiplies it as a compensation; `off` turns off the
    /// scene's [default: the scene's `[post] auto_exposure`, else off].
    #[arg(long, value_name = "KEY|off", num_args = 0..=1, default_missing_value = "on",
          value_parser = parse_key_or_off)]
    pub auto_exposure: Option<crate::scene::Stage>,
    /// Auto exposure: fraction of the way (in log exposure) to the target per frame [default:
    /// the scene's `[post] exposure_adaptation`, else 0.05].
    #[arg(long, value_name = "F")]
    pub exposure_adaptation: Option<f32>,
    /// Triangular dither of ±1/255 before the 8-bit quantization (no banding on gradients)
    /// [default: the scene's `[post] dither`, else off].
    #[arg(long, value_enum, value_name = "on|off", num_args = 0..=1, default_missing_value = "on")]
    pub dither: Option<Toggle>,
    /// Bloom: moves the share STRENGTH of the radiance into a wide blur (energy-conserving,
    /// no threshold); `off` turns off the scene's [default: the scene's `[post] bloom`, else
    /// off].
    #[arg(long, value_name = "STRENGTH|off", value_parser = parse_strength_or_off)]
    pub bloom: Option<crate::scene::Stage>,
    /// FXAA on the tone-mapped image [default: the scene's `[post] fxaa`, else off].
    #[arg(long, value_enum, value_name = "on|off", num_args = 0..=1, default_missing_value = "on")]
    pub fxaa: Option<Toggle>,
}

impl PostArgs {
    /// The flags given (`--tonemap` and `--exposure` are the frame's, filled in by
    /// [`FrameArgs::settings`]).
    pub fn overrides(&self) -> crate::scene::PostOverrides {
        crate::scene::PostOverrides {
            taa: self.taa.map(Toggle::on),
            taa_history_weight: self.taa_history_weight,
            taa_frames: self.taa_frames,
            auto_exposure: self.auto_exposure,
            exposure_adaptation: self.exposure_adaptation,
            bloom: self.bloom,
            fxaa: self.fxaa.map(Toggle::on),
            dither: self.dither.map(Toggle::on),
            tonemap: None,
            exposure: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `render`'s frame flags alone.
    #[derive(clap::Parser)]
    struct Frame {
        #[command(flatten)]
        frame: FrameArgs,
    }

    fn parse(args: &[&str]) -> FrameArgs {
        use clap::Parser as _;
        Frame::try_parse_from([&["voxgi"], args].concat())
            .expect("parses")
            .frame
    }

    fn render_gi(args: &[&str]) -> GiOverrides {
        parse(args).gi.overrides()
    }

    fn render_settings(args: &[&str]) -> RenderSettings {
        let scene = crate::scene::load_scene_arg(None).expect("the built-in scene");
        parse(args).settings(&scene).expect("settings")
    }

    #[test]
    fn voxel_flags_apply_to_gi_and_debug_grids_without_voxels() {
        let v = render_settings(&["--gi", "pathtrace", "--revoxelize", "--voxel-layers", "2"])
            .voxels
            .expect("GI voxelizes");
        assert!(v.revoxelize_static && v.layers == 2, "{v:?}");
        let v = render_settings(&["--debug", "voxels", "--voxelizer", "atlas"])
            .voxels
            .expect("the voxel view voxelizes");
        assert_eq!(v.voxelizer, crate::voxel::gpu::Voxelizer::Atlas);
        // The built-in scene's `[gi]` table path-traces; direct light needs no voxels.
        assert!(render_settings(&["--gi", "none", "--debug", "atlas"])
            .voxels
            .is_none());
        assert!(render_settings(&["--gi", "none"]).voxels.is_none());
    }

    #[test]
    fn projection_flags_override_the_scene_camera_and_bad_values_name_the_flag() {
        use crate::scene::Projection;
        let load = |args: &[&str]| parse(args).camera.load_scene(None);
        let default = load(&[]).expect("loads");
        assert_eq!(default.camera.projection, Projection::Perspective);
        let s = load(&["--projection", "orthographic", "--ortho-height", "0.75"]).expect("loads");
        assert_eq!(
            (s.camera.projection, s.camera.ortho_height_m),
            (Projection::Orthographic, 0.75)
        );
        // Without --ortho-height the scene's (here its default) height stays.
        let s = load(&["--projection", "orthographic"]).expect("loads");
        assert_eq!(s.camera.ortho_height_m, default.camera.ortho_height_m);
        for bad in ["0", "-1", "NaN", "inf"] {
            let Err(e) = load(&["--ortho-height", bad]) else {
                panic!("--ortho-height {bad} accepted");
            };
            assert!(e.to_string().contains("--ortho-height"), "{bad}: {e}");
        }
        use clap::Parser as _;
        let Err(e) = Frame::try_parse_from(["voxgi", "--projection", "isometric"]) else {
            panic!("--projection isometric accepted");
        };
        assert!(e.to_string().contains("orthographic"), "{e}");
    }

    #[test]
    fn transparency_flag_overrides_the_scene_key_and_defaults_to_oit() {
        use crate::scene::Transparency;
        let mut scene = crate::scene::load_scene_arg(None).expect("the built-in scene");
        let mode = |scene: &Scene, args: &[&str]| parse(args).settings(scene).expect("settings");
        assert_eq!(mode(&scene, &[]).transparency, Transparency::Oit);
        scene.transparency = Some(Transparency::Hashed);
        assert_eq!(mode(&scene, &[]).transparency, Transparency::Hashed);
        let flag = mode(
            &scene,
            &["--transparency", "oit", "--oit-nodes-per-pixel", "9"],
        );
        assert_eq!(flag.transparency, Transparency::Oit);
        assert_eq!(flag.oit_nodes_per_pixel, 9);
        let err = parse(&["--oit-nodes-per-pixel", "0"]).settings(&scene);
        assert!(err.is_err_and(|e| e.to_string().contains("--oit-nodes-per-pixel")));
    }

    #[test]
    fn post_flags_override_the_scene_post_table() {
        use crate::post::{PostSettings, TaaSettings, ToneMap};
        use crate::scene::{PostOverrides, Stage};
        let plain = crate::scene::load_scene_arg(None).expect("the built-in scene");
        // No table, no flags: everything off, the default tone map.
        let s = parse(&[]).settings(&plain).expect("settings");
        assert_eq!(
            (s.post, s.tonemap),
            (PostSettings::default(), ToneMap::default())
        );
        let s = parse(&["--taa", "--dither", "--auto-exposure", "--bloom", "0.1"])
            .settings(&plain)
            .expect("settings");
        assert_eq!(s.post.taa, Some(TaaSettings::default()));
        assert_eq!(
            s.post.auto_exposure,
            Some(crate::post::AutoExposure::default())
        );
        assert_eq!(s.post.bloom, Some(0.1));
        assert!(s.tonemap.dither && !s.post.fxaa);
        let mut scene = plain.clone();
        scene.post = PostOverrides {
            taa: Some(true),
            taa_frames: Some(4),
            auto_exposure: Some(Stage::On(None)),
            exposure_adaptation: Some(0.5),
            bloom: Some(Stage::On(Some(0.2))),
            fxaa: Some(true),
            dither: Some(true),
            tonemap: Some(ToneOperator::Drago),
            exposure: Some(2.0),
            ..Default::default()
        };
        // The table alone.
        let s = parse(&[]).settings(&scene).expect("settings");
        let taa = s.post.taa.expect("the scene's TAA");
        assert_eq!(
            (taa.frames, taa.history_weight),
            (4, TaaSettings::default().history_weight)
        );
        let ae = s.post.auto_exposure.expect("the scene's auto exposure");
        assert_eq!(
            (ae.key, ae.adaptation),
            (crate::post::AutoExposure::default().key, 0.5)
        );
        assert_eq!((s.post.bloom, s.post.fxaa), (Some(0.2), true));
        assert_eq!(
            (s.tonemap.operator, s.tonemap.exposure, s.tonemap.dither),
            (ToneOperator::Drago, 2.0, true)
        );
        // Flags win, `off` included; the table fills in what they leave out.
        let s = parse(&[
            "--taa",
            "off",
            "--bloom",
            "off",
            "--fxaa",
            "off",
            "--dither",
            "off",
            "--tonemap",
            "linear",
            "--exposure",
            "3",
            "--auto-exposure",
            "0.5",
        ])
        .settings(&scene)
        .expect("settings");
        assert_eq!((s.post.taa, s.post.bloom, s.post.fxaa), (None, None, false));
        let ae = s.post.auto_exposure.expect("on");
        assert_eq!((ae.key, ae.adaptation), (0.5, 0.5));
        assert_eq!(
            (s.tonemap.operator, s.tonemap.exposure, s.tonemap.dither),
            (ToneOperator::Linear, 3.0, false)
        );
        let s = parse(&["--taa-frames", "2", "--auto-exposure", "off"])
            .settings(&scene)
            .expect("settings");
        assert_eq!(s.post.taa.map(|t| t.frames), Some(2));
        assert_eq!(s.post.auto_exposure, None);
        // `--auto-exposure` alone switches on and keeps the scene's key.
        scene.post.auto_exposure = Some(Stage::On(Some(0.3)));
        let s = parse(&["--auto-exposure"])
            .settings(&scene)
            .expect("settings");
        assert_eq!(s.post.auto_exposure.map(|a| a.key), Some(0.3));
        // Out-of-range flags name the flag.
        let e = parse(&["--bloom", "2"])
            .settings(&scene)
            .expect_err("out of range");
        assert!(e.to_string().contains("--bloom = 2"), "{e}");
    }

    #[test]
    fn sao_flags_override_the_scene_keys() {
        let plain = crate::scene::load_scene_arg(None).expect("the built-in scene");
        assert_eq!(parse(&[]).settings(&plain).expect("settings").gi.sao, None);
        let mut scene = plain.clone();
        scene.gi.sao = crate::scene::SaoOverrides {
            enabled: Some(true),
            radius_m: Some(0.5),
            ..Default::default()
        };
        let sao = |args: &[&str]| parse(args).settings(&scene).expect("settings").gi.sao;
        let d = crate::gi::SaoSettings::default();
        assert_eq!(sao(&[]).map(|s| (s.radius_m, s.bias)), Some((0.5, d.bias)));
        assert_eq!(sao(&["--sao", "off"]), None);
        assert_eq!(sao(&["--sao-radius", "0.7"]).map(|s| s.radius_m), Some(0.7));
        assert_eq!(sao(&["--sao-show"]).map(|s| s.view), Some(true));
        // SAO's values without SAO on would do nothing: an error naming the way out.
        for args in [
            &["--sao-radius", "1"][..],
            &["--sao-show"],
            &["--sao", "off", "--sao-bias", "0.1"],
        ] {
            let e = parse(args).settings(&plain).expect_err("SAO is off");
            assert!(e.to_string().contains("add --sao"), "{args:?}: {e}");
        }
    }

    #[test]
    fn gi_flags_not_given_leave_the_scene_values() {
        assert!(render_gi(&[]).is_empty());
        let scene = GiOverrides {
            method: Some(GiMethod::Pathtrace),
            rays: Some(4),
            bounces: Some(crate::gi::Bounces::Fixed(3)),
            ..Default::default()
        };
        let s = resolve_gi(&scene, &render_gi(&[]));
        assert_eq!(
            (s.method, s.rays, s.bounces),
            (GiMethod::Pathtrace, 4, crate::gi::Bounces::Fixed(3))
        );
        let s = resolve_gi(
            &scene,
            &render_gi(&["--gi", "hemisphere", "--gi-rays", "32", "--gi-frames", "8"]),
        );
        assert_eq!(
            (s.method, s.rays, s.bounces, s.accumulate_frames),
            (GiMethod::Hemisphere, 32, crate::gi::Bounces::Fixed(3), 8)
        );
    }

    #[test]
    fn every_gi_flag_maps_to_its_field() {
        let o = render_gi(&[
            "--gi",
            "pathtrace",
            "--gi-rays",
            "2",
            "--gi-bounces",
            "3",
            "--gi-radius",
            "0.5",
            "--gi-normal-offset",
            "0.25",
            "--gi-ray-offset",
            "1.5",
            "--gi-filter-radius",
            "6",
            "--gi-filter-passes",
            "7",
            "--gi-frames",
            "9",
            "--light-map-resolution",
            "128",
            "--vpls",
            "5",
            "--vpl-pattern",
            "8x2",
            "--vpl-bounces",
            "3",
            "--vpl-d-min",
            "1.5",
            "--vpl-min-roughness",
            "0.35",
            "--vpl-visibility",
            "none",
            "--vpl-normalize",
            "valid",
            "--vpl-spot-sampling",
            "disk",
            "--ssgi-resolution",
            "quarter",
            "--ssgi-samples",
            "17",
            "--ssgi-mips",
            "fast",
            "--ssgi-no-feedback",
            "--ssgi-feedback-max",
            "4.5",
            "--ssgi-history-weight",
            "0.3",
            "--ssr",
            "off",
            "--ssr-rays",
            "lobe",
            "--sao",
            "--sao-radius",
            "0.6",
            "--sao-bias",
            "0.03",
            "--sao-contrast",
            "1.5",
            "--sao-epsilon",
            "0.02",
        ]);
        assert_eq!(
            o,
            GiOverrides {
                method: Some(GiMethod::Pathtrace),
                rays: Some(2),
                bounces: Some(crate::gi::Bounces::Fixed(3)),
                radius_m: Some(0.5),
                normal_offset_voxels: Some(0.25),
                ray_offset_voxels: Some(1.5),
                filter_radius: Some(6),
                filter_passes: Some(7),
                light_map_resolution: Some(128),
                accumulate_frames: Some(9),
                vpl: crate::gi::vpl::VplOverrides {
                    per_set: Some(5),
                    pattern: Some([8, 2]),
                    bounces: Some(3),
                    d_min_voxels: Some(1.5),
                    min_roughness: Some(0.35),
                    visibility: Some(crate::gi::vpl::VplVisibility::None),
                    normalize: Some(crate::gi::vpl::VplNormalize::Valid),
                    spot_sampling: Some(crate::gi::vpl::VplSpotSampling::Disk),
                },
                ssgi: crate::scene::SsgiOverrides {
                    resolution: Some(crate::gi::SsgiResolution::Quarter),
                    samples: Some(17),
                    mips: Some(crate::gi::SsgiMips::Fast),
                    feedback: Some(false),
                    feedback_max_w_m2: Some(4.5),
                    history_weight: Some(0.3),
                    ssr: Some(false),
                    ssr_rays: Some(crate::gi::SsrRays::Lobe),
                },
                sao: crate::scene::SaoOverrides {
                    enabled: Some(true),
                    radius_m: Some(0.6),
                    bias: Some(0.03),
                    contrast: Some(1.5),
                    epsilon_m2: Some(0.02),
                },
            }
        );
    }
}

/// `--shadow-resolution`: texels per side, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadowResolutionArg {
    Texels(u32),
    Auto,
}

impl std::str::FromStr for ShadowResolutionArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Self::Auto),
            n => n
                .parse()
                .map(Self::Texels)
                .map_err(|_| format!("`{n}`: expected texels per side (e.g. 1024) or `auto`")),
        }
    }
}

impl std::fmt::Display for ShadowResolutionArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Texels(n) => write!(f, "{n}"),
            Self::Auto => f.write_str("auto"),
        }
    }
}
