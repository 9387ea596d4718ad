//! Scenes: the TOML scene format, OBJ/MTL meshes, textures, camera, lights, materials,
//! animation, and the built-in scenes. Pure Rust; the renderer uploads what [`Scene`] holds.
//!
//! # Units and conventions
//! Meters; linear RGB; right-handed world, y up. Point and spot lights give radiant intensity
//! in W/sr (E = I cosθ / d²), directional lights irradiance in W/m². Spot falloff, light units
//! and the camera FOV follow Mitsuba 3 (except that `fov_y_deg` is always *vertical*;
//! Mitsuba's default `fov_axis` is "x", see [`Camera::fov_x_deg`]). Materials are Lambert plus
//! normalized Phong, f = ρ/π + ρs (n+2)/(2π) cosⁿα.
//!
//! # Scene file format
//! Every key below is listed; any other key is an error. Relative paths resolve against the
//! scene file's directory. Error messages name fields as `objects[2].scale` (0-based).
//!
//! ```toml
//! transparency = "oit"              # optional: how the camera view draws materials with
//!                                   #   d < 1, "oit" (linked lists, default) or "hashed";
//!                                   #   `--transparency` overrides it
//! [camera]                          # optional only when an object's glTF has a camera (the
//!                                   #   first glTF object's first camera is used)
//! position = [0.278, 0.273, -0.80]  # meters
//! target = [0.278, 0.273, 0.0]      # a point to look at, or instead:
//! # forward = [0.0, 0.0, 1.0]       # a viewing direction (not both)
//! up = [0.0, 1.0, 0.0]              # optional, default +Y; must not be parallel to the view
//! fov_y_deg = 39.3                  # vertical field of view, degrees in (0, 180); optional
//!                                   #   with projection = "orthographic" (default 40)
//! projection = "perspective"        # optional: "perspective" (default) or "orthographic";
//!                                   #   `--projection` overrides it
//! ortho_height_m = 0.6              # orthographic: the view's height in meters (required
//!                                   #   there); its width is height × width / height of the
//!                                   #   image. Optional under perspective (what `--projection
//!                                   #   orthographic` and the viewer's toggle use; default the
//!                                   #   view's height at the depth of the scene's centre)
//! near = 0.01                       # optional, default 0.01 m
//! far = 100.0                       # optional, default 100 m; near < far
//!
//! [[lights]]                        # zero or more
//! kind = "spot"                     # "point" | "spot" | "directional"
//! position = [0.278, 0.54, 0.28]    # point, spot
//! direction = [0.0, -1.0, 0.0]      # spot (cone axis), directional (direction of travel)
//! intensity_w_sr = [1.0, 1.0, 1.0]  # point, spot: W/sr, >= 0 (a single number means gray)
//! cutoff_deg = 30.0                 # spot: cone half-angle in (0, 90); Mitsuba `cutoff_angle`;
//!                                   #   default 20
//! beam_deg = 20.0                   # spot: full-intensity half-angle in (0, cutoff];
//!                                   #   Mitsuba `beam_width`; default 3/4 of cutoff
//!
//! [[lights]]
//! kind = "directional"
//! direction = [-0.3, -1.0, 0.2]
//! irradiance_w_m2 = [2.0, 2.0, 2.0] # W/m² on a surface facing the light
//!
//! [[lights]]                        # area lights: Mitsuba `rectangle` / `sphere` shapes with
//! kind = "rectangle"                #   an `area` emitter; "rectangle" | "sphere"
//! position = [0.0, 1.8, 0.3]        # the center
//! radiance_w_sr_m2 = 12.0           # emitted radiance, W/(m²·sr), >= 0
//! normal = [0.0, -1.0, 0.0]         # rectangle: the one side that emits
//! width_m = 0.8                     # rectangle: > 0, along width_axis
//! height_m = 0.4                    # rectangle: > 0, along normal × width_axis
//! width_axis = [1.0, 0.0, 0.0]      # rectangle, optional: default +Y × normal (+Z × normal
//!                                   #   for a vertical normal), projected into the plane
//! # radius_m = 0.12                 # sphere: > 0, emits outward everywhere
//! samples = 16                      # optional, default 16, in [1, 64]: sub-lights (one
//!                                   #   shadow view each) it is rendered with; --area-samples
//!                                   #   overrides it for every area light
//!
//! [[objects]]                       # at least one
//! name = "bunny"                    # optional, for the UI and logs
//! mesh = "../meshes/bunny.obj"      # an OBJ file (its MTL and textures beside it), or a
//!                                   #   glTF 2.0 file (`.gltf`, `.glb`; docs/gltf.md): its
//!                                   #   default scene's node tree flattened, this object's
//!                                   #   transform applied on top; its KHR_lights_punctual
//!                                   #   lights join `[[lights]]` (placed at time 0), its
//!                                   #   first camera serves when there is no `[camera]`;
//!                                   #   or:
//! crease_deg = 60.0                 # OBJ without `vn` or `s` lines, glTF primitives without
//!                                   #   NORMAL: faces meeting at more than this stay sharp,
//!                                   #   vertices split [60]
//! # builtin = "cube"                # "cube" (1 m, centered), "quad" (1 m², XZ plane, facing
//!                                   #   +Y), "sphere" (diameter 1 m), "cornell_walls",
//!                                   #   "cornell_short_block", "cornell_tall_block"
//! translate = [0.278, 0.0, 0.28]    # optional; model matrix = T · R · S
//! rotate_deg = [0.0, 90.0, 0.0]     # optional, about X first, then Y, then Z (world axes)
//! scale = 0.02                      # optional, a number or [x, y, z], non-zero
//! material = { albedo = [0.8, 0.8, 0.8], specular = [0.1, 0.1, 0.1], shininess = 40.0 }
//!                                   # optional: replaces these MTL fields on every submesh;
//!                                   #   also `opacity` in [0, 1]; an `albedo` drops `map_Kd`;
//!                                   #   `roughness`, `metallic` (each in [0, 1]) make it GGX
//!                                   #   metal/roughness (MTL `Pr`, `Pm`; not together with
//!                                   #   `specular`/`shininess`); `emission_w_sr_m2` (>= 0, a
//!                                   #   number or RGB, MTL `Ke`) is emitted radiance
//! dynamic = true                    # optional: re-voxelized every frame (default: animated)
//!
//! [objects.animation]               # optional; keyframes or an OBJ sequence
//! loop = true                       # optional, default true
//! keyframes = [
//!     { time_s = 0.0, translate = [0.2, 0.0, 0.3] },
//!     { time_s = 2.0, translate = [0.4, 0.0, 0.3], rotate_deg = [0.0, 180.0, 0.0], scale = 0.03 },
//! ]                                 # times strictly increasing; a key's missing fields take
//!                                   # the object's values; translation and scale are
//!                                   # interpolated linearly, rotation by slerp
//!
//! [[objects]]
//! name = "flag"
//! [objects.animation]
//! obj_sequence = "anim/flag_{:03}.obj"  # `{}` or `{:0N}` is replaced by the frame number
//! frames = 24                           # >= 1; every frame must share the first's topology
//! fps = 24.0                            # optional, default 24
//! first_frame = 1                       # optional, default 0
//!
//! [camera_path]                     # optional: a flight `voxgi profile --camera-path` replays
//! up = [0.0, 1.0, 0.0]              # optional, default the camera's `up`
//! keyframes = [                     # at least 2; times finite and strictly increasing
//!     { time_s = 0.0, position = [0.278, 0.273, -0.8], look_at = [0.278, 0.273, 0.0] },
//!     { time_s = 2.0, position = [0.1, 0.35, -0.2], direction = [0.3, -0.4, 0.9], fov_y_deg = 50.0 },
//! ]                                 # `look_at` (a point) or `direction`, not both; optional
//!                                   #   fov_y_deg in (0, 180), default the camera's
//!                                   # position, direction and fov follow a Catmull-Rom spline
//!                                   #   in time (C1, through every key; see [`CameraPath`]);
//!                                   #   outside the keys' times the path holds its ends
//!
//! [voxel]    # optional: the voxel grid, when something needs one (a GI method, the
//!            #   emitters' or the environment's direct light, a voxel debug view); flags
//!            #   (`--voxels`, `--voxel-layers`, …) override it
//! resolution = 256                  # at most N columns per side, 1..=16384; voxels are
//!                                   #   near-cubic, so the longest side gets N [128]
//! layers = 2                        # depth layers of 128 voxels, 1..=64 [1]
//! voxelizer = "triangle"            # "triangle" | "atlas" ["triangle"]
//! revoxelize = false                # static geometry every frame too [false]
//!
//! [gi]       # optional: the scene's indirect-light defaults; every key optional (default
//!            #   in brackets); command-line flags (`--gi`, `--gi-rays`, …) override them
//! method = "pathtrace"              # "none" | "hemisphere" | "pathtrace" | "vpl" ["none"]
//! rays = 16                         # rays per pixel, 1..=4096 [16]
//! bounces = 2                       # path-tracer bounces, 1..=64, or "unbounded": 3 bounces,
//!                                   #   then Russian roulette (unbiased; capped at 64) [2]
//! radius_m = 1.5                    # ray length in meters, > 0 [the scene's diagonal]
//! normal_offset_voxels = 1.0        # start offset along the normal, voxel diagonals >= 0 [1]
//! ray_offset_voxels = 0.0           # start offset along the ray, voxel diagonals >= 0 [0]
//! filter_radius = 4                 # geometry-aware filter radius, pixels 0..=64, 0 off [4]
//! filter_passes = 2                 # filter passes (horizontal + vertical), 0..=16 [2]
//! light_map_resolution = 256        # reflective light-map texels per side, 16..=8192 [256]
//! accumulate_frames = 1             # frames a headless path-tracer render accumulates [1]
//! vpls = 16                         # VPLs per interleaving set and light, 1..=1024 [16]
//! vpl_pattern = [4, 4]              # interleaving pattern N x M, each 1..=16 [[4, 4]]
//! vpl_bounces = 2                   # VPL bounces, 1..=8 [2]
//! vpl_d_min_voxels = 8.0            # d_min of the VPL falloff, voxel diagonals >= 0 [8]
//! vpl_min_roughness = 0.4           # glossy receivers' roughness floor under VPLs, 0..=1 [0.4]
//! vpl_visibility = "voxel"          # "voxel" (segment test) | "none" ["voxel"]
//! vpl_normalize = "all"             # VPL flux over "all" K samples | the "valid" ones ["all"]
//! vpl_spot_sampling = "solid-angle" # spot VPLs "solid-angle" (cone) | "disk" (image plane)
//! ssgi_resolution = "half"          # screen-space GI resolution: "full" | "half" | "quarter"
//!                                   #   | "eighth" ["half"]
//! ssgi_samples = 64                 # screen-space GI samples per texel and level, 1..=1024 [64]
//! sao = true                        # modified SAO (Oetke 2017 §2.5) multiplied into the
//!                                   #   indirect light; needs a method [false]; --sao [on|off]
//! sao_radius_m = 1.8                # SAO sample radius r, meters > 0 [1.8]; --sao-radius
//! sao_bias = 0.04                   # SAO bias β, meters of v·n >= 0 [0.04]; --sao-bias
//! sao_contrast = 2.0                # SAO contrast exponent k, 0..=64 [2]; --sao-contrast
//! sao_epsilon_m2 = 0.01             # SAO ε of v·v + ε, m² > 0 [0.01]; --sao-epsilon
//!
//! [environment]                     # optional: light from far away, seen by camera rays that
//!                                   #   miss (the background) and by GI rays that leave the
//!                                   #   voxel grid within their radius; black without it
//! kind = "constant"                 # "constant" | "map" | "sky"
//! radiance = [0.8, 0.9, 1.0]        # constant: W/(m²·sr), >= 0 (a number means gray);
//!                                   #   Mitsuba's `constant` emitter
//! # file = "sky.hdr"                # map: an equirectangular (2:1) Radiance .hdr or OpenEXR
//!                                   #   image of linear radiance; Mitsuba's `envmap` (+Y up,
//!                                   #   the top row up, u = 0 along −Z, u = 1/4 along +X; see
//!                                   #   [`environment`])
//! # rotation_deg = 0.0              # map, optional: turn about +Y, counter-clockwise seen
//!                                   #   from above, degrees [0]
//! # scale = 1.0                     # map, sky, optional: factor on the radiance, >= 0 [1]
//! # turbidity = 3.0                 # sky: Hosek–Wilkie turbidity, 1..=10 [3]; the sky's sun
//!                                   #   is the first directional light (required; its
//!                                   #   irradiance is the sun's, the sky adds no sun disk);
//!                                   #   Mitsuba's `sunsky` with sun_scale 0 (see [`sky`])
//! # ground_albedo = 0.3             # sky: ground albedo under the atmosphere, 0..=1 or
//!                                   #   [r, g, b] [0.3]
//!
//! [shadow]   # optional: shadow defaults; `--shadow-cascades`, `--shadow-cascade-lambda` override
//! cascades = 4                      # cascades per directional light (camera's direct light),
//!                                   #   1..=8; 1: the single whole-scene map [4]
//! cascade_lambda = 0.5              # splits: logarithmic (1) to uniform (0) blend, 0..=1 [0.5]
//!
//! [post]     # optional: post-processing defaults; each flag of the same name overrides its
//!            #   key (`--taa off`, `--bloom off`, `--auto-exposure off` turn a stage off)
//! taa = true                        # temporal anti-aliasing [false]
//! taa_history_weight = 0.9          # TAA history weight α, 0..=0.999 [0.9]
//! taa_frames = 16                   # frames a headless TAA render runs, 1..=4096 [16]
//! auto_exposure = 0.18              # auto exposure's key value (> 0, <= 1000), true (key
//!                                   #   0.18) or false [false]
//! exposure_adaptation = 0.05        # auto exposure's adaptation per frame, (0, 1] [0.05]
//! bloom = 0.05                      # bloom strength in [0, 1], or false [false]
//! fxaa = true                       # FXAA after tone mapping [false]
//! dither = true                     # ±1/255 triangular dither before 8 bits [false]
//! tonemap = "filmic"                # "linear" | "logarithmic" | "drago" | "filmic" ["filmic"]
//! exposure = 1.0                    # exposure factor (a compensation with auto exposure),
//!                                   #   > 0 [1]
//! ```
//!
//! A missing texture (or MTL file) is not an error: it is logged with `log::warn!` and the
//! material's color is used. Everything else that is wrong is a [`SceneError`] naming the
//! file and the field or line.
//!
//! # Built-in scenes
//! [`builtin()`] returns `cornell` (the default: Cornell box lit by a spot light) and
//! `cornell-point` (the same box with a point light). They are parsed from the embedded
//! `assets/scenes/cornell.toml` through the same code path as files.

pub mod atrium;
mod builtin;
mod camera;
mod camera_path;
mod crease;
mod cull;
mod desc;
pub mod environment;
mod error;
mod gi;
mod gi_settings;
mod gltf;
mod gltf_asset;
mod light;
mod material;
mod mesh;
mod obj;
mod object;
mod post_settings;
pub mod pre_exposure;
mod query;
pub mod save;
pub mod schema;
mod shadow_settings;
pub mod sky;
mod sky_data;
mod voxel_settings;
pub mod vpl_settings;

use std::path::{Path, PathBuf};

pub use builtin::{
    builtin, builtin_names, builtin_toml, default_gi_layer, load_scene_arg, DEFAULT_SCENE,
};
pub use camera::{look_to, perspective, Camera, Eye, Projection, StereoRig};
pub use camera_path::{CameraKey, CameraPath, CameraPathError};
pub use cull::aabb_visible;
pub use desc::gi_table_layer;
pub use environment::{Environment, EnvironmentMap};
pub use error::SceneError;
pub use gi::resolve_gi;
pub use gi_settings::{
    range as gi_range, Bounces, GiFilterKind, GiMethod, GiSettings, RadianceSource, SaoSettings,
    SsgiMips, SsgiResolution, SsgiSettings, SsrRays,
};
pub use gltf::{is_gltf_path, LUMENS_PER_WATT, SUPPORTED_REQUIRED_EXTENSIONS};
pub use light::{scaled, spot_falloff, Light};
pub use material::{
    fresnel_schlick, ggx_brdf, ggx_d, ggx_diffuse, ggx_g1, ggx_specular, AlphaMap, AlphaMode,
    BumpKind, Ggx, Material, PbrMaps, TextureData, Transparency, DIELECTRIC_F0, TRANSPARENCY_NAMES,
};
pub use mesh::{
    area_weighted_normals, corner_order, orient_to_normals, Aabb, Mesh, SubMesh, BUILTIN_MESH_NAMES,
};
pub use object::{
    euler_xyz_deg, rotation_from_euler_xyz_deg, Animation, Keyframe, Object, Transform,
};
pub use post_settings::{
    range as post_range, AutoExposure, DynamicResolution, PostSettings, PostTable, TaaSettings,
    ToneMap, ToneOperator, Upscale, MOVING_GI_RAYS,
};
pub use pre_exposure::PreExposure;
pub use query::NoSuchObject;
pub use shadow_settings::{
    range as shadow_range, AreaShadow, PointShadow, ShadowSettings, AUTO_RESOLUTION_NAME,
    DEFAULT_CASCADES,
};
pub use voxel_settings::{VoxelSettings, Voxelizer};
pub use vpl_settings::{VplSettings, VplShading, VplVisibility};

/// A loaded, validated scene: everything finite, directions unit length, indices in range.
#[derive(Clone, Debug)]
pub struct Scene {
    /// World position of the scene's local origin, meters (f64): everything below is
    /// relative to it (a floating origin, chosen at load by `desc::local_origin`; zero for
    /// scenes within 128 m of the world origin). Add it to report or save world positions.
    pub origin_m: glam::DVec3,
    pub camera: Camera,
    /// The `[camera_path]` table: a flight `voxgi profile --camera-path` replays.
    pub camera_path: Option<CameraPath>,
    pub lights: Vec<Light>,
    pub objects: Vec<Object>,
    /// Shared by objects; OBJ sequences contribute one mesh per frame.
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureData>,
    /// The `[voxel]` table: the scene's layer of the voxel grid's settings (flags override
    /// it; the keys are [`VoxelSettings::keys`](schema::Settings::keys)); see
    /// [`Scene::voxel_settings`].
    pub voxel: schema::Layer,
    /// The `[gi]` table: the scene's layer of the indirect-light settings (nothing given
    /// without the table); see [`resolve_gi`].
    pub gi: schema::Layer,
    /// The top-level `transparency` key ("oit" or "hashed"): how the camera view draws
    /// surfaces with d < 1 unless `--transparency` says otherwise; `None` without the key.
    pub transparency: Option<Transparency>,
    /// The `[shadow]` table: the scene's layer of the shadow settings (flags override it;
    /// the keys are [`ShadowSettings::keys`](schema::Settings::keys)).
    pub shadow: schema::Layer,
    /// The `[post]` table: the scene's layer of the post-processing settings (flags override
    /// it; the keys are [`PostTable::keys`](schema::Settings::keys)).
    pub post: schema::Layer,
    /// The `[environment]` table: the light from far away (the background and what GI rays
    /// leaving the voxel grid read); `None`: black, as without the table.
    pub environment: Option<Environment>,
    /// The scene file; `None` for built-in scenes.
    pub source: Option<PathBuf>,
}

impl Scene {
    /// The voxel grid's settings of this scene: the defaults under its `[voxel]` table. What
    /// a renderer voxelizes with when something needs voxels and the frame's settings name
    /// none (`RenderSettings::voxels`).
    pub fn voxel_settings(&self) -> VoxelSettings {
        schema::resolve(&[&self.voxel])
    }

    /// Loads a TOML scene file and everything it references, or a glTF or OBJ file as a scene
    /// of its own ([`Scene::load_model`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        if is_gltf_path(path) || obj::is_obj_path(path) {
            return Scene::load_model(path);
        }
        let text = obj::read_text(path, "scene file", None)?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        let desc = desc::parse(&text, path)?;
        desc::build(desc, path, base_dir, Some(path.to_path_buf()))
    }

    /// A scene made from a glTF or OBJ file alone (`voxgi render x.glb`, `voxgi render
    /// x.obj`): one object holding the file (a glTF's default scene with its
    /// `KHR_lights_punctual` lights), the glTF's first camera, else a camera framing its bounds
    /// from the front (+Z) and a little above. A file without lights and without emissive
    /// materials gets a default sun (with a warning): model viewers light such models by
    /// default, and a black picture would look like a broken import; a scene file naming the
    /// model as an object's `mesh` gets no sun and sets its own lights.
    pub fn load_model(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let base_dir = path.parent().unwrap_or(Path::new("."));
        let file_name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let desc = desc::SceneDesc {
            camera: None,
            lights: Vec::new(),
            objects: vec![desc::ObjectDesc {
                mesh: Some(file_name),
                ..Default::default()
            }],
            voxel: None,
            gi: None,
            shadow: None,
            post: None,
            camera_path: None,
            transparency: None,
            environment: None,
        };
        let fallbacks = desc::SceneFallbacks {
            frame_camera: true,
            default_sun: true,
        };
        // No TOML file to save edits into: the viewer treats it like a built-in scene.
        desc::build_with(desc, path, base_dir, None, fallbacks)
    }

    /// Parses scene TOML from a string. `origin` names it in error messages; relative paths
    /// resolve against `base_dir`.
    pub fn from_toml_str(text: &str, origin: &Path, base_dir: &Path) -> Result<Scene, SceneError> {
        let desc = desc::parse(text, origin)?;
        desc::build(desc, origin, base_dir, None)
    }

    /// Bounds of all objects at time `t_s`.
    pub fn aabb_at(&self, t_s: f32) -> Aabb {
        self.objects
            .iter()
            .fold(Aabb::EMPTY, |b, o| b.union(o.aabb_at(t_s)))
    }

    /// The orthographic view height a camera without `ortho_height_m` switches to: the
    /// perspective view's height at the view depth of the scene's centre (at time 0), so the
    /// switch keeps the size of what lies there; the view height at 1 m when the centre is not
    /// in front of the camera.
    pub fn default_ortho_height_m(&self) -> f32 {
        let b = self.aabb_at(0.0);
        let depth = ((b.min + b.max) * 0.5 - self.camera.position).dot(self.camera.forward);
        let depth = if depth.is_finite() && depth > self.camera.near {
            depth
        } else {
            1.0
        };
        self.camera
            .view_height_at(depth)
            .clamp(1e-6, crate::limits::ORTHO_HEIGHT_M.max)
    }

    /// Materials drawn by some object.
    pub fn used_materials(&self) -> impl Iterator<Item = &Material> {
        self.objects
            .iter()
            .flat_map(|o| o.materials.iter())
            .filter_map(|&m| self.materials.get(m))
    }

    /// No drawn material has a specular lobe (Phong or GGX).
    pub fn is_all_lambert(&self) -> bool {
        self.used_materials().all(Material::is_lambert)
    }

    /// Some drawn material has a normalized-Phong lobe: the Phong passes are needed.
    pub fn has_phong(&self) -> bool {
        self.used_materials().any(Material::is_phong)
    }

    /// Some drawn material is GGX metal/roughness: the G-buffer carries its parameters.
    pub fn has_ggx(&self) -> bool {
        self.used_materials().any(|m| m.ggx.is_some())
    }

    /// Some drawn material emits: the G-buffer carries emission.
    pub fn has_emission(&self) -> bool {
        self.used_materials().any(Material::is_emissive)
    }

    /// Point lights need cube shadow maps.
    pub fn has_point_lights(&self) -> bool {
        self.lights.iter().any(Light::is_point)
    }

    pub fn has_spot_lights(&self) -> bool {
        self.lights.iter().any(Light::is_spot)
    }

    pub fn has_directional_lights(&self) -> bool {
        self.lights.iter().any(Light::is_directional)
    }

    /// Some object must be re-voxelized every frame.
    pub fn has_dynamic_objects(&self) -> bool {
        self.objects.iter().any(|o| o.dynamic)
    }

    /// Some object moves by itself (keyframes or an OBJ sequence).
    pub fn has_animation(&self) -> bool {
        self.objects.iter().any(Object::is_animated)
    }

    /// Some drawn material samples an albedo texture.
    pub fn has_albedo_textures(&self) -> bool {
        self.used_materials().any(|m| m.draw_texture().is_some())
    }

    /// Some drawn material has per-texel alpha ([`Material::alpha_map`]): the passes that
    /// rasterize materials test it (a specialization constant, so other scenes skip it).
    pub fn has_alpha_maps(&self) -> bool {
        self.used_materials().any(|m| m.alpha_map.is_some())
    }

    /// Some drawn material has a bump or normal map.
    pub fn has_bump_maps(&self) -> bool {
        self.used_materials().any(|m| m.bump_texture.is_some())
    }

    /// Some drawn material has an MTL PBR map (`map_Pr`, `map_Pm`, `map_Ke`).
    pub fn has_pbr_maps(&self) -> bool {
        self.used_materials()
            .any(|m| m.pbr_maps != material::PbrMaps::default())
    }

    /// Some drawn material is not fully opaque.
    pub fn has_transparency(&self) -> bool {
        self.used_materials().any(|m| !m.is_opaque())
    }

    /// Total triangles drawn at time `t_s`.
    pub fn triangle_count_at(&self, t_s: f32) -> usize {
        self.objects
            .iter()
            .filter_map(|o| self.meshes.get(o.mesh_at(t_s)))
            .map(Mesh::triangle_count)
            .sum()
    }
}

#[cfg(test)]
mod fuzz_tests;
#[cfg(test)]
mod gltf_tests;
#[cfg(test)]
mod input_tests;
#[cfg(test)]
mod material_tests;
#[cfg(test)]
mod tests;
