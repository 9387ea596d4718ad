//! The flags shared by several commands, and their conversion into the renderer's settings.

use crate::gi::GiMethod;
use crate::gi::GiSettings;
use crate::post::{PostSettings, ToneMap};
use crate::render::RenderSettings;
use crate::scene::schema::{Flag, FlagStyle, Key, Kind, Layer, Settings, Value};
use crate::scene::{resolve_gi, PostTable, Scene, ShadowSettings, VoxelSettings};

/// The named flags of a settings table's keys (`S::keys`), generated from the table: each
/// key's flag, with its help, value name and values from the key's row. Each one given
/// overrides the scene file's value, which overrides the default.
#[derive(Clone, Debug, Default)]
pub struct KeyFlags<S: Settings> {
    /// The named flags given, in the table's order, as their keys' values (not yet checked
    /// against the ranges: [`KeyFlags::layer`] does that, naming the flag).
    pub given: Vec<(&'static Key<S>, Value)>,
}

/// The `[post]` keys' flags (`--taa`, `--bloom`, `--tonemap`, …).
pub type PostArgs = KeyFlags<PostTable>;
/// The `[shadow]` keys' flags (`--shadow-resolution`, `--pcf-radius`, …).
pub type ShadowArgs = KeyFlags<ShadowSettings>;
/// The `[voxel]` keys' flags (`--voxels`, `--voxel-layers`, `--voxelizer`, `--revoxelize`).
pub type VoxelArgs = KeyFlags<VoxelSettings>;

/// Indirect-light flags of `render`, `profile`, `graph`, `sweep`'s configurations and `view`:
/// the `[gi]` keys' named flags ([`GiSettings::keys`]), `--set KEY=VALUE` for every key of
/// every table, and the GI debug views.
#[derive(Clone, Debug, Default)]
pub struct GiArgs {
    pub flags: KeyFlags<GiSettings>,
    /// `--set KEY=VALUE`, as typed, in the order given (applied after the named flags; each
    /// table's layer takes its own keys).
    pub set: Vec<String>,
    /// `--gi vpl`: debug view, every VPL drawn as a dot over the image.
    pub vpl_show: bool,
    /// SAO debug view: the AO term as grey instead of the image.
    pub sao_show: bool,
}

const SET_ID: &str = "set";
const VPL_SHOW_ID: &str = "vpl-show";
const SAO_SHOW_ID: &str = "sao-show";

/// The tables `--set` reaches.
const SET_TABLES: [&str; 4] = [
    GiSettings::TABLE,
    PostTable::TABLE,
    ShadowSettings::TABLE,
    VoxelSettings::TABLE,
];

/// Every key path `--set` takes, for its help and its error.
fn set_paths() -> String {
    [
        crate::scene::schema::paths::<GiSettings>(),
        crate::scene::schema::paths::<PostTable>(),
        crate::scene::schema::paths::<ShadowSettings>(),
        crate::scene::schema::paths::<VoxelSettings>(),
    ]
    .concat()
    .join(", ")
}

/// What a key's flag help says its default is: "the scene's `[gi] rays`, else 16".
fn default_words<S: Settings>(k: &Key<S>) -> String {
    let v = (k.get)(&S::default());
    let text = match v {
        Value::Bool(true) => "on".to_owned(),
        Value::Bool(false) => "off".to_owned(),
        v => k.kind.to_text(v),
    };
    let scene = format!("the scene's `[{}] {}`", S::TABLE, k.name());
    // The built-in scene's GI lies under a scene that names no method (FrameArgs::settings).
    match crate::scene::default_gi_layer().get(k.path) {
        Some(d) if k.path == "gi.method" => format!(
            "{scene}, else {} (the built-in scene's GI)",
            k.kind.to_text(d)
        ),
        Some(d) => format!(
            "{scene}, else {text}, or {} where no method is named",
            k.kind.to_text(d)
        ),
        None => format!("{scene}, else {text}"),
    }
}

/// The named flag of key `k`.
fn key_arg<S: Settings>(k: &'static Key<S>, f: Flag) -> clap::Arg {
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
        (FlagStyle::OptionalValue, _) => arg
            .value_name(f.value_name)
            .num_args(0..=1)
            .default_missing_value("on")
            .value_parser(move |s: &str| kind.parse(s)),
        (FlagStyle::Value, Kind::Choice(values)) => arg
            .value_name(f.value_name)
            .value_parser(PossibleValuesParser::new(values()).try_map(read)),
        (FlagStyle::Value, _) => arg
            .value_name(f.value_name)
            .value_parser(move |s: &str| kind.parse(s)),
    }
}

impl<S: Settings> clap::FromArgMatches for KeyFlags<S> {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut a = KeyFlags { given: Vec::new() };
        a.update_from_arg_matches(m)?;
        Ok(a)
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        for k in S::keys() {
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
        Ok(())
    }
}

impl<S: Settings> clap::Args for KeyFlags<S> {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        S::keys()
            .iter()
            .filter_map(|k| Some(key_arg(k, k.flag?)))
            .fold(cmd, clap::Command::arg)
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl<S: Settings> KeyFlags<S> {
    /// The command line's layer of `S`: the named flags, then the entries of `set`
    /// (`--set KEY=VALUE`, in the order given) of `S`'s table, each checked against its key's
    /// range and named as the user typed it (the flag, or the key path). A `--set` key of no
    /// table is an error listing every key.
    pub fn layer(&self, set: &[String]) -> Result<Layer, super::CliError> {
        let mut layer = Layer::default();
        for (k, v) in &self.given {
            layer.set(k.path, k.kind.check(&k.flag_name(), *v)?);
        }
        for s in set {
            let (path, value) = s.split_once('=').unwrap_or((s.as_str(), ""));
            let path = path.trim();
            let table = path.split_once('.').map_or("", |(t, _)| t);
            if table != S::TABLE && SET_TABLES.contains(&table) {
                continue;
            }
            let k =
                crate::scene::schema::key::<S>(path).ok_or_else(|| crate::limits::LimitError {
                    name: "--set".into(),
                    value: s.clone(),
                    expected: format!("KEY=VALUE with KEY one of {}", set_paths()),
                })?;
            layer.set(k.path, k.kind.parse_checked(k.path, value)?);
        }
        Ok(layer)
    }

    /// `base` under the scene's layer of `S` (`scene`), under the command line's (these flags
    /// and `set`): the frame's settings of `S`.
    pub fn apply(&self, base: S, scene: &Layer, set: &[String]) -> Result<S, super::CliError> {
        Ok(crate::scene::schema::apply(
            base,
            &[scene, &self.layer(set)?],
        ))
    }
}

impl clap::FromArgMatches for GiArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut a = GiArgs::default();
        a.update_from_arg_matches(m)?;
        Ok(a)
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        self.flags.update_from_arg_matches(m)?;
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
        KeyFlags::<GiSettings>::augment_args(cmd)
            .arg(
                Arg::new(SET_ID)
                    .long("set")
                    .value_name("KEY=VALUE")
                    .action(ArgAction::Append)
                    .help(
                        "Sets any `[gi]`, `[post]`, `[shadow]` or `[voxel]` key by its path, as the scene file's table would (e.g. --set gi.rays=8, --set post.bloom=0.3); repeatable, applied after the named flags",
                    )
                    .long_help(format!(
                        "Sets any `[gi]`, `[post]`, `[shadow]` or `[voxel]` key by its path, as the scene file's table would (e.g. --set gi.rays=8, --set post.bloom=0.3); repeatable, applied after the named flags. Keys: {}",
                        set_paths()
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
    /// The command line's layer of `[gi]`: the named flags, then `--set`'s `gi.` keys.
    pub fn layer(&self) -> Result<Layer, super::CliError> {
        self.flags.layer(&self.set)
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

    /// The scene's `[gi]` values, overridden by the flags given. Where neither names a
    /// method, the built-in default scene's GI (the path tracer) lies under both.
    pub fn settings(&self, scene: &Scene) -> Result<crate::gi::GiSettings, super::CliError> {
        let cli = self.layer()?;
        let names_method = |l: &Layer| l.iter().any(|(p, _)| p == "gi.method");
        let s = if names_method(&scene.gi) || names_method(&cli) {
            resolve_gi(&scene.gi, &cli)
        } else {
            let default = crate::scene::default_gi_layer();
            crate::scene::schema::resolve(&[&default, &scene.gi, &cli])
        };
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

    /// The scene's `[post]` values over `post` and `tone`, overridden by the `[post]` flags
    /// (`flags`) and `--set`'s `post.` keys; with the viewer's dynamic resolution.
    pub fn post(
        &self,
        flags: &PostArgs,
        scene: &Scene,
        post: PostSettings,
        tonemap: ToneMap,
    ) -> Result<PostTable, super::CliError> {
        let t = PostTable {
            post,
            tonemap,
            ..Default::default()
        };
        flags.apply(t, &scene.post, &self.set)
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
    /// Surfaces with MTL d < 1 in the camera view: per-pixel linked lists sorted and blended
    /// (oit), or hashed alpha testing (hashed); default: the scene's `transparency` key, else
    /// oit. Shadow and light maps always use hashed alpha.
    #[arg(long, value_enum)]
    pub transparency: Option<crate::scene::Transparency>,
    /// Capacity of the transparency node buffer in layers per pixel on average (more
    /// fragments are dropped and reported).
    #[arg(long, value_name = "N", default_value_t = crate::render::OIT_DEFAULT_NODES_PER_PIXEL)]
    pub oit_nodes_per_pixel: u32,
    // The voxel grid (over the scene's `[voxel]` table): `--voxels N` voxelizes even without
    // GI (static geometry once, dynamic objects in the frames they move; `profile` then shows
    // those voxel passes).
    #[command(flatten)]
    pub voxel: VoxelArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub gi: GiArgs,
    #[command(flatten)]
    pub post: PostArgs,
    #[command(flatten)]
    pub shadow: ShadowArgs,
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
        let t = self.gi.post(&self.post, scene, s.post, s.tonemap)?;
        (s.post, s.tonemap) = (t.post, t.tonemap);
        s.shadow = self.shadow.apply(s.shadow, &scene.shadow, &self.gi.set)?;
        s.transparency = self.transparency.or(scene.transparency).unwrap_or_default();
        s.oit_nodes_per_pixel =
            crate::limits::OIT_NODES_PER_PIXEL.check_flag(self.oit_nodes_per_pixel)?;
        s.gi = self.gi.settings(scene)?;
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
        // What needs voxels (a GI method, the emitters' or the environment's direct light, a
        // voxel debug view) voxelizes with the scene's `[voxel]` under the voxel flags and
        // `--set voxel.*`; `--voxels N` voxelizes even when nothing does (to measure the voxel
        // passes). Every GI method, screen-space GI too, voxelizes.
        let voxel = self.voxel.layer(&self.gi.set)?;
        let forced = self
            .voxel
            .given
            .iter()
            .any(|(k, _)| k.path == "voxel.resolution");
        let needs_voxels = s.gi.method != GiMethod::None || crate::render::needs_voxels(&s, scene);
        s.voxels = (needs_voxels || forced)
            .then(|| crate::scene::schema::resolve(&[&scene.voxel, &voxel]));
        self.gi.check_sao(&s.gi)?;
        crate::render::check_render_settings(&s)?;
        Ok(s)
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

    /// A scene with emitters voxelizes for their direct light under `--gi none`, with the
    /// command line's `[voxel]` keys over the scene's table.
    #[test]
    fn the_emitters_direct_light_voxelizes_with_the_command_lines_voxel_keys() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/assets/scenes/cornell_emissive.toml"
        );
        let scene = crate::scene::Scene::load(path).expect("loads");
        let v = parse(&["--gi", "none", "--set", "voxel.resolution=64"])
            .settings(&scene)
            .expect("settings")
            .voxels
            .expect("the emitters' direct light voxelizes");
        assert_eq!((v.max_res_xy, v.layers), (64, 1));
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
        use crate::post::{PostSettings, TaaSettings, ToneMap, ToneOperator};
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
        scene.post = text_layer::<PostTable>(&[
            ("post.taa", "true"),
            ("post.taa_frames", "4"),
            ("post.auto_exposure", "true"),
            ("post.exposure_adaptation", "0.5"),
            ("post.bloom", "0.2"),
            ("post.fxaa", "true"),
            ("post.dither", "true"),
            ("post.tonemap", "drago"),
            ("post.exposure", "2"),
        ]);
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
        scene.post.set("post.auto_exposure", Value::Number(0.3));
        let s = parse(&["--auto-exposure"])
            .settings(&scene)
            .expect("settings");
        assert_eq!(s.post.auto_exposure.map(|a| a.key), Some(0.3));
        // Out-of-range flags name the flag.
        let e = parse(&["--bloom", "2"])
            .settings(&scene)
            .expect_err("out of range");
        assert!(e.to_string().contains("--bloom = 2"), "{e}");
        // `--set` reaches every `[post]` key, after the named flags.
        let s = parse(&["--bloom", "0.1", "--set", "post.bloom=0.3"])
            .settings(&plain)
            .expect("settings");
        assert_eq!(s.post.bloom, Some(0.3));
        let e = parse(&["--set", "post.bloom=2"])
            .settings(&plain)
            .expect_err("out of range");
        assert!(e.to_string().starts_with("post.bloom = 2"), "{e}");
    }

    #[test]
    fn shadow_flags_override_the_scene_shadow_table() {
        let plain = crate::scene::load_scene_arg(None).expect("the built-in scene");
        let s = parse(&[]).settings(&plain).expect("settings");
        assert_eq!(s.shadow, ShadowSettings::default());
        let mut scene = plain.clone();
        scene.shadow = text_layer::<ShadowSettings>(&[
            ("shadow.cascades", "2"),
            ("shadow.pcf_radius", "3"),
            ("shadow.resolution", "auto"),
        ]);
        let s = parse(&[]).settings(&scene).expect("settings").shadow;
        assert_eq!((s.cascades, s.pcf_radius, s.auto_resolution), (2, 3, true));
        let s = parse(&["--shadow-resolution", "512", "--set", "shadow.cascades=1"])
            .settings(&scene)
            .expect("settings")
            .shadow;
        assert_eq!(
            (s.cascades, s.pcf_radius, s.resolution, s.auto_resolution),
            (1, 3, 512, false)
        );
        let s = parse(&["--area-samples", "4", "--point-shadows", "paraboloid"])
            .settings(&plain)
            .expect("settings")
            .shadow;
        assert_eq!(
            (s.area_samples, s.point_technique),
            (Some(4), crate::light::PointShadow::DualParaboloid)
        );
    }

    /// A layer of `S` from `(path, text)` pairs, read as `--set` reads them.
    fn text_layer<S: Settings>(values: &[(&str, &str)]) -> Layer {
        let mut l = Layer::default();
        for (path, text) in values {
            let k = crate::scene::schema::key::<S>(path).expect(path);
            l.set(k.path, k.kind.parse_checked(path, text).expect(text));
        }
        l
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

    /// A scene that names no GI method renders with the built-in scene's GI (the path
    /// tracer, 4 rays × 2 frames, unbounded, filter 8) under its own `[gi]` keys and the
    /// flags; a method named by the scene or a flag keeps the built-in defaults under it.
    #[test]
    fn a_scene_without_a_method_gets_the_default_scenes_gi() {
        let mut scene =
            crate::scene::builtin("cornell-point").expect("a built-in without a [gi] table");
        assert!(scene.gi.get("gi.method").is_none());
        let gi = |scene: &Scene, args: &[&str]| parse(args).gi.settings(scene).expect("settings");
        let d = GiSettings::default();
        let s = gi(&scene, &[]);
        assert_eq!(
            (
                s.method,
                s.rays,
                s.accumulate_frames,
                s.bounces,
                s.filter_radius
            ),
            (GiMethod::Pathtrace, 4, 2, crate::gi::Bounces::Unbounded, 8)
        );
        // The flags and the scene's own keys still win over that layer.
        let s = gi(&scene, &["--gi-rays", "16"]);
        assert_eq!((s.method, s.rays), (GiMethod::Pathtrace, 16));
        scene.gi.set("gi.bounces", Value::Count(2));
        assert_eq!(gi(&scene, &[]).bounces, crate::gi::Bounces::Fixed(2));
        // `--gi none` is direct light with the built-in defaults, not the layer's.
        let s = gi(&scene, &["--gi", "none"]);
        assert_eq!((s.method, s.rays), (GiMethod::None, d.rays));
        // A scene that names a method keeps the defaults under its table.
        scene.gi.set("gi.method", Value::Choice(1));
        let s = gi(&scene, &[]);
        assert_eq!((s.method, s.rays), (GiMethod::Hemisphere, d.rays));
    }

    /// Every flag of every table is a key's, with the key's range: each flag given a value
    /// other than the default's sets its key to it, `--set` reaches the same key with the same
    /// value, and one past the key's range is refused naming the flag (or, by `--set`, the
    /// key path). A new row is covered here without an edit.
    fn every_flag_maps_to_its_key_and_range<S: Settings>(
        table_layer: fn(&FrameArgs) -> Result<Layer, crate::cli::CliError>,
    ) -> usize {
        use crate::scene::schema::Kind;
        let d = S::default();
        let layer = |args: &[&str]| table_layer(&parse(args)).expect("in range");
        let mut flags = 0;
        for k in S::keys() {
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
                (_, Kind::Count(l) | Kind::CountOr(l, ..) | Kind::OptCount(l, _), _) => {
                    let n = if l.min == 2 {
                        3
                    } else {
                        l.min.max(2).min(l.max)
                    };
                    (vec![flag.clone(), n.to_string()], Value::Count(n))
                }
                (_, Kind::Pair(_), _) => (vec![flag.clone(), "2x3".into()], Value::Pair([2, 3])),
                (_, Kind::Number(_) | Kind::OptNumber(..) | Kind::Switch(..), _) => {
                    (vec![flag.clone(), "0.375".into()], Value::Number(0.375))
                }
                other => panic!("{flag}: no test value for {other:?}"),
            };
            let args: Vec<&str> = text.iter().map(String::as_str).collect();
            let given = layer(&args);
            assert_eq!(given.iter().collect::<Vec<_>>(), [(k.path, want)], "{flag}");
            let set = format!("{}={}", k.path, k.kind.to_text(want));
            assert_eq!(layer(&["--set", &set]), given, "{set}");
            let past = match k.kind {
                Kind::Count(l) | Kind::CountOr(l, ..) | Kind::OptCount(l, _) => {
                    Some((l.max + 1).to_string())
                }
                Kind::Number(l) | Kind::OptNumber(l, _) | Kind::Switch(l, _) => {
                    Some(format!("{}", l.max * 2.0))
                }
                Kind::Pair(l) => Some(format!("{}x1", l.max + 1)),
                _ => None,
            };
            if let Some(past) = past {
                let e = table_layer(&parse(&[&flag, &past]))
                    .expect_err(&flag)
                    .to_string();
                assert!(e.starts_with(&format!("{flag} = ")), "{e}");
                assert!(e.contains(&k.kind.expected()), "{e}");
                let set = format!("{}={past}", k.path);
                let e = table_layer(&parse(&["--set", &set]))
                    .expect_err(&set)
                    .to_string();
                assert!(e.starts_with(&format!("{} = ", k.path)), "{e}");
            }
        }
        flags
    }

    #[test]
    fn every_gi_flag_maps_to_its_key_and_range() {
        let flags = every_flag_maps_to_its_key_and_range::<GiSettings>(|a| a.gi.layer());
        assert!(flags >= 30, "{flags} GI flags");
        // Later values win: `--set` after the named flag.
        let l = render_gi(&["--gi-rays", "4", "--set", "gi.rays=8", "--set", "gi.rays=9"]);
        assert_eq!(l.get("gi.rays"), Some(Value::Count(9)));
        let e = parse(&["--set", "gi.rayz=2"])
            .gi
            .layer()
            .expect_err("unknown");
        assert!(e.to_string().contains("gi.rays"), "{e}");
        // A key of no table names every table's keys.
        let e = parse(&["--set", "post.blom=0.1"])
            .settings(&crate::scene::load_scene_arg(None).expect("built in"))
            .expect_err("unknown");
        for path in ["gi.rays", "post.bloom", "shadow.resolution"] {
            assert!(e.to_string().contains(path), "{e}");
        }
    }

    /// `--set` reaches every key of the four tables, the keys without a flag too: each key's
    /// default, written as a scene file writes it, reads back as that key's value.
    #[test]
    fn set_reaches_every_key_of_every_table() {
        fn each<S: Settings>(
            table_layer: fn(&FrameArgs) -> Result<Layer, crate::cli::CliError>,
        ) -> usize {
            let d = S::default();
            for k in S::keys() {
                // An unset default reads as words ("the scene's diagonal"): set the largest.
                let v = match ((k.get)(&d), k.kind) {
                    (Value::Unset, Kind::OptNumber(l, _)) => Value::Number(l.max),
                    (Value::Unset, Kind::OptCount(l, _)) => Value::Count(l.max),
                    (v, _) => v,
                };
                let set = format!("{}={}", k.path, k.kind.to_text(v));
                let layer = table_layer(&parse(&["--set", &set])).expect(&set);
                assert_eq!(layer.iter().collect::<Vec<_>>(), [(k.path, v)], "{set}");
            }
            S::keys().len()
        }
        let keys = each::<GiSettings>(|a| a.gi.layer())
            + each::<PostTable>(|a| a.post.layer(&a.gi.set))
            + each::<ShadowSettings>(|a| a.shadow.layer(&a.gi.set))
            + each::<VoxelSettings>(|a| a.voxel.layer(&a.gi.set));
        assert!(keys >= 60, "{keys} keys");
    }

    #[test]
    fn every_post_and_shadow_flag_maps_to_its_key_and_range() {
        let post = every_flag_maps_to_its_key_and_range::<PostTable>(|a| a.post.layer(&a.gi.set));
        assert!(post >= 10, "{post} [post] flags");
        let shadow =
            every_flag_maps_to_its_key_and_range::<ShadowSettings>(|a| a.shadow.layer(&a.gi.set));
        assert!(shadow >= 7, "{shadow} [shadow] flags");
    }
}
