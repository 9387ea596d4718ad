//! The flags shared by several commands, and their conversion into the renderer's settings.

use crate::gi::GiMethod;
use crate::gi::GiSettings;
use crate::light::PointShadow;
use crate::post::ToneOperator;
use crate::render::RenderSettings;
use crate::scene::schema::{Flag, FlagStyle, Key, Kind, Layer, Settings, Value};
use crate::scene::{resolve_gi, Scene};

/// Indirect-light flags of `render`, `profile`, `graph`, `sweep`'s configurations and `view`,
/// generated from the `[gi]` key table ([`GiSettings::keys`]): each key's named flag (its
/// help, value name and values from the table), and `--set KEY=VALUE` for every key. Each
/// one given overrides the scene file's `[gi]` value, which overrides the default.
#[derive(Clone, Debug, Default)]
pub struct GiArgs {
    /// The named flags given, in the table's order, as their keys' values (not yet checked
    /// against the ranges: [`GiArgs::layer`] does that, naming the flag).
    pub given: Vec<(&'static Key<GiSettings>, Value)>,
    /// `--set KEY=VALUE`, as typed, in the order given (applied after the named flags).
    pub set: Vec<String>,
    /// `--gi vpl`: debug view, every VPL drawn as a dot over the image.
    pub vpl_show: bool,
    /// SAO debug view: the AO term as grey instead of the image.
    pub sao_show: bool,
}

const SET_ID: &str = "set";
const VPL_SHOW_ID: &str = "vpl-show";
const SAO_SHOW_ID: &str = "sao-show";

/// What a key's flag help says its default is: "the scene's `[gi] rays`, else 16".
fn default_words(k: &Key<GiSettings>) -> String {
    let v = (k.get)(&GiSettings::default());
    let text = match v {
        Value::Bool(true) => "on".to_owned(),
        Value::Bool(false) => "off".to_owned(),
        v => k.kind.to_text(v),
    };
    format!(
        "the scene's `[{}] {}`, else {text}",
        GiSettings::TABLE,
        k.name()
    )
}

/// The named flag of key `k`.
fn key_arg(k: &'static Key<GiSettings>, f: Flag) -> clap::Arg {
    use clap::builder::{PossibleValuesParser, TypedValueParser as _};
    use clap::{Arg, ArgAction};
    let help = format!("{} [default: {}]", k.doc, default_words(k));
    let arg = Arg::new(k.path).long(f.long).help(help);
    let kind = k.kind;
    let read = move |s: String| kind.parse(&s);
    match (f.style, kind) {
        (FlagStyle::SetsFalse, _) => arg.action(ArgAction::SetTrue),
        (FlagStyle::Toggle, _) => arg
            .value_name(f.value_name)
            .num_args(0..=1)
            .default_missing_value("on")
            .value_parser(PossibleValuesParser::new(["on", "off"]).try_map(read)),
        (FlagStyle::Value, Kind::Choice(values)) => arg
            .value_name(f.value_name)
            .value_parser(PossibleValuesParser::new(values()).try_map(read)),
        (FlagStyle::Value, _) => arg
            .value_name(f.value_name)
            .value_parser(move |s: &str| kind.parse(s)),
    }
}

impl clap::FromArgMatches for GiArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut a = GiArgs::default();
        a.update_from_arg_matches(m)?;
        Ok(a)
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        for k in GiSettings::keys() {
            let Some(f) = k.flag else { continue };
            let v = match f.style {
                FlagStyle::SetsFalse => m.get_flag(k.path).then_some(Value::Bool(false)),
                _ => m.try_get_one::<Value>(k.path).ok().flatten().copied(),
            };
            if let Some(v) = v {
                self.given.retain(|(g, _)| g.path != k.path);
                self.given.push((k, v));
            }
        }
        if let Ok(Some(set)) = m.try_get_many::<String>(SET_ID) {
            self.set.extend(set.cloned());
        }
        self.vpl_show |= m.get_flag(VPL_SHOW_ID);
        self.sao_show |= m.get_flag(SAO_SHOW_ID);
        Ok(())
    }
}

impl clap::Args for GiArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        use clap::{Arg, ArgAction};
        let mut cmd = cmd;
        for k in GiSettings::keys() {
            if let Some(f) = k.flag {
                cmd = cmd.arg(key_arg(k, f));
            }
        }
        let paths = crate::scene::schema::paths::<GiSettings>().join(", ");
        cmd.arg(
            Arg::new(SET_ID)
                .long("set")
                .value_name("KEY=VALUE")
                .action(ArgAction::Append)
                .help(
                    "Sets any `[gi]` key by its path, as the scene file's table would (e.g. --set gi.rays=8, --set gi.vpl_pattern=2x2); repeatable, applied after the named flags",
                )
                .long_help(format!(
                    "Sets any `[gi]` key by its path, as the scene file's table would (e.g. --set gi.rays=8, --set gi.vpl_pattern=2x2); repeatable, applied after the named flags. Keys: {paths}"
                )),
        )
        .arg(
            Arg::new(VPL_SHOW_ID)
                .long("vpl-show")
                .action(ArgAction::SetTrue)
                .help(
                    "`--gi vpl`: debug view, every VPL drawn as a dot over the image (first bounce yellow, later ones cyan)",
                ),
        )
        .arg(
            Arg::new(SAO_SHOW_ID)
                .long("sao-show")
                .action(ArgAction::SetTrue)
                .help(
                    "SAO debug view: the AO term as grey (1 white = unoccluded) instead of the image (needs SAO on, by --sao or the scene)",
                ),
        )
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl GiArgs {
    /// The command line's layer: the named flags, then `--set`, each checked against its
    /// key's range and named as the user typed it (the flag, or the key path).
    pub fn layer(&self) -> Result<Layer, super::CliError> {
        let mut layer = Layer::default();
        for (k, v) in &self.given {
            layer.set(k.path, k.kind.check(&k.flag_name(), *v)?);
        }
        for s in &self.set {
            let (path, value) = s.split_once('=').unwrap_or((s.as_str(), ""));
            let k = crate::scene::schema::key::<GiSettings>(path.trim()).ok_or_else(|| {
                crate::limits::LimitError {
                    name: "--set".into(),
                    value: s.clone(),
                    expected: format!(
                        "KEY=VALUE with KEY one of {}",
                        crate::scene::schema::paths::<GiSettings>().join(", ")
                    ),
                }
            })?;
            layer.set(k.path, k.kind.parse_checked(k.path, value)?);
        }
        Ok(layer)
    }

    /// SAO's value flags and `--sao-show` need SAO on (by `--sao` or the scene's `[gi] sao`):
    /// given while it is off they would do nothing, which is an error naming them.
    pub fn check_sao(&self, s: &crate::gi::GiSettings) -> Result<(), super::CliError> {
        let layer = self.layer()?;
        let values = layer.iter().any(|(p, _)| p.starts_with("gi.sao_"));
        if s.sao.is_none() && (values || self.sao_show) {
            return Err(super::CliError::SaoOff);
        }
        Ok(())
    }

    /// The scene's `[gi]` values, overridden by the flags given.
    pub fn settings(&self, scene: &Scene) -> Result<crate::gi::GiSettings, super::CliError> {
        let s = resolve_gi(&scene.gi, &self.layer()?);
        Ok(crate::gi::GiSettings {
            vpl: crate::gi::vpl::VplSettings {
                show: self.vpl_show,
                ..s.vpl
            },
            sao: s.sao.map(|a| crate::gi::SaoSettings {
                view: self.sao_show,
                ..a
            }),
            ..s
        })
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
        s.gi = self.gi.settings(scene)?;
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

    fn render_gi(args: &[&str]) -> Layer {
        parse(args).gi.layer().expect("in range")
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
        scene.gi.set("gi.sao", Value::Bool(true));
        scene.gi.set("gi.sao_radius_m", Value::Number(0.5));
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
            &["--set", "gi.sao_contrast=3"],
        ] {
            let e = parse(args).settings(&plain).expect_err("SAO is off");
            assert!(e.to_string().contains("add --sao"), "{args:?}: {e}");
        }
    }

    #[test]
    fn gi_flags_not_given_leave_the_scene_values() {
        assert!(render_gi(&[]).is_empty());
        let mut scene = Layer::default();
        scene.set("gi.method", Value::Choice(2));
        scene.set("gi.rays", Value::Count(4));
        scene.set("gi.bounces", Value::Count(3));
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

    /// Every GI flag is a key's, with the key's range: each flag given a value other than the
    /// default's sets its key to it, and one past the key's range is refused naming the flag.
    #[test]
    fn every_gi_flag_maps_to_its_key_and_range() {
        use crate::scene::schema::Kind;
        let d = GiSettings::default();
        let mut flags = 0;
        for k in GiSettings::keys() {
            let Some(f) = k.flag else { continue };
            flags += 1;
            let flag = format!("--{}", f.long);
            let (text, want): (Vec<String>, Value) = match (f.style, k.kind, (k.get)(&d)) {
                (FlagStyle::SetsFalse, ..) => (vec![flag.clone()], Value::Bool(false)),
                (FlagStyle::Toggle, _, Value::Bool(b)) => {
                    let t = if b { "off" } else { "on" };
                    (vec![flag.clone(), t.into()], Value::Bool(!b))
                }
                (_, Kind::Choice(_), Value::Choice(i)) => {
                    let other = usize::from(i == 0);
                    let name = k.kind.names()[other].clone();
                    (vec![flag.clone(), name], Value::Choice(other))
                }
                (_, Kind::Count(l), _) | (_, Kind::CountOr(l, ..), _) => {
                    let n = if l.min == 2 {
                        3
                    } else {
                        l.min.max(2).min(l.max)
                    };
                    (vec![flag.clone(), n.to_string()], Value::Count(n))
                }
                (_, Kind::Pair(_), _) => (vec![flag.clone(), "2x3".into()], Value::Pair([2, 3])),
                (_, Kind::Number(_) | Kind::OptNumber(..), _) => {
                    (vec![flag.clone(), "0.375".into()], Value::Number(0.375))
                }
                other => panic!("{flag}: no test value for {other:?}"),
            };
            let args: Vec<&str> = text.iter().map(String::as_str).collect();
            let layer = render_gi(&args);
            assert_eq!(layer.iter().collect::<Vec<_>>(), [(k.path, want)], "{flag}");
            // `--set` reaches the same key with the same value.
            let set = format!("{}={}", k.path, k.kind.to_text(want));
            assert_eq!(render_gi(&["--set", &set]), layer, "{set}");
            // One past the range: the flag's error names the flag, `--set`'s the key.
            let past = match k.kind {
                Kind::Count(l) | Kind::CountOr(l, ..) => Some((l.max + 1).to_string()),
                Kind::Number(l) | Kind::OptNumber(l, _) => Some(format!("{}", l.max * 2.0)),
                Kind::Pair(l) => Some(format!("{}x1", l.max + 1)),
                _ => None,
            };
            if let Some(past) = past {
                let e = parse(&[&flag, &past])
                    .gi
                    .layer()
                    .expect_err(&flag)
                    .to_string();
                assert!(e.starts_with(&format!("{flag} = ")), "{e}");
                assert!(e.contains(&k.kind.expected()), "{e}");
                let set = format!("{}={past}", k.path);
                let e = parse(&["--set", &set])
                    .gi
                    .layer()
                    .expect_err(&set)
                    .to_string();
                assert!(e.starts_with(&format!("{} = ", k.path)), "{e}");
            }
        }
        assert!(flags >= 30, "{flags} GI flags");
        // Later values win: `--set` after the named flag.
        let l = render_gi(&["--gi-rays", "4", "--set", "gi.rays=8", "--set", "gi.rays=9"]);
        assert_eq!(l.get("gi.rays"), Some(Value::Count(9)));
        let e = parse(&["--set", "gi.rayz=2"])
            .gi
            .layer()
            .expect_err("unknown");
        assert!(e.to_string().contains("gi.rays"), "{e}");
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
