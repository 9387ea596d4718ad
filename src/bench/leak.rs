//! The light-leak benchmark (`voxgi bench leak`): two closed rooms side by side, split by one
//! solid wall a given number of GI voxels thick, a spot light in room A only. No light can
//! reach room B, so the truth there is exactly zero; whatever indirect light a method shows
//! in B has leaked through the wall.
//!
//! **Leaked fraction** of a method at a wall: the mean indirect radiance of room B's image
//! divided by the mean indirect radiance of the mirrored view in room A (the camera reflected
//! in the wall's middle plane), both over all pixels and the three channels. Indirect radiance
//! is the method's image minus the direct-only image (`--gi none`) of the same view; in room B
//! the direct image is checked to be exactly zero, so there it is the method's image itself.
//!
//! **Exact wall thickness in voxels.** The rooms are long along z (`ROOM_DEPTH_M`, the
//! scene's longest edge whatever the wall), so the voxel edge h that
//! [`crate::voxel::VoxelGrid::around`] derives from the longest edge does not depend on the
//! wall; the wall of t·h is centred on x = 0, the scene's centre, and each room's width is
//! grown by h/2 steps until the grid's x resolution has the parity that puts x = 0 on a voxel
//! centre (t = 2, 4 and t < 1: the faces sit symmetric in voxels, a whole t voxels apart) or
//! on a voxel plane (t = 1: both faces on voxel centres). [`LeakScene::face_phases`] reports
//! where the faces lie in their voxels; the construction fails unless both are at least a
//! fifth of a voxel from every voxel plane, so rounding cannot move a face into another voxel.

use super::BenchError;
use crate::eval::HdrImage;
use crate::gi::{GiMethod, GiSettings, RadianceSource};
use crate::render::{render_image, RenderSettings};
use crate::scene::Scene;
use crate::vk::Context;
use crate::voxel::gpu::VoxelSettings;
use glam::Vec3;
use serde::Serialize;

/// Depth (z) of both rooms, meters: the scene's longest edge, fixing the voxel size.
pub const ROOM_DEPTH_M: f32 = 1.0;
/// Height (y) of both rooms, meters.
pub const ROOM_HEIGHT_M: f32 = 0.5;
/// Smallest width (x) of each room, meters; grown by up to one voxel (see the module doc).
pub const ROOM_MIN_WIDTH_M: f32 = 0.42;
/// The wall thicknesses of the benchmark, in voxels of the GI grid.
pub const DEFAULT_WALLS_VOXELS: [f32; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];
/// The least distance of a wall face from a voxel plane, in voxels.
const MIN_FACE_CLEARANCE_VOXELS: f32 = 0.2;

/// Where room A's spot light shines. Either way no point of room B can be lit directly, and
/// [`direct_images`] checks that B's direct image is exactly 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum LeakLight {
    /// Faces the dividing wall from 0.35 m at mid height; its 30° cone lights a disk of
    /// radius 0.35·tan 30° = 0.20 m < 0.25 m on the wall, clear of floor, ceiling and side
    /// walls. Points of room B inside the cone lie behind that disk (the wall's B face faces
    /// away from the light) or on B's floor and ceiling at least 0.25/tan 30° − 0.35 = 0.08 m
    /// behind the wall: 8 cm deeper than the occluder in the shadow map, far beyond its bias.
    Wall,
    /// Hangs 2 cm before the wall at 0.9 of the height and points down and away from it, 45°
    /// below the horizontal, with a 45° cone: it lights room A's floor up to 2 cm from the
    /// wall, and every direction in its cone has x ≤ its own x, so no point of room B (x > 0)
    /// is inside the cone, whatever the shadow maps do.
    Floor,
}

impl LeakLight {
    /// Position, direction and cone (cutoff, beam) in degrees, for room A's interior box
    /// ending at `a_hi`.
    fn spot(self, a_hi: Vec3) -> (Vec3, Vec3, f32, f32) {
        let (h, d) = (ROOM_HEIGHT_M, ROOM_DEPTH_M);
        match self {
            LeakLight::Wall => (
                Vec3::new(a_hi.x - 0.35, 0.5 * h, 0.5 * d),
                Vec3::X,
                30.0,
                25.0,
            ),
            LeakLight::Floor => (
                Vec3::new(a_hi.x - 0.02, 0.9 * h, 0.5 * d),
                Vec3::new(-1.0, -1.0, 0.0).normalize(),
                45.0,
                40.0,
            ),
        }
    }
}

/// One scene of the family and the facts its construction guarantees.
#[derive(Clone, Debug)]
pub struct LeakScene {
    /// The scene with the camera in room B.
    pub scene_b: Scene,
    /// The same scene with the camera mirrored into room A.
    pub scene_a: Scene,
    /// Wall thickness in voxels and in meters.
    pub wall_voxels: f32,
    pub light: LeakLight,
    pub wall_m: f32,
    /// The voxel edge of the GI grid, meters.
    pub voxel_m: f32,
    /// Room B's interior box (room A is its mirror image in x = 0).
    pub room_b_min: Vec3,
    pub room_b_max: Vec3,
}

impl LeakScene {
    /// Where the wall's two faces lie inside their voxels along x (0 and 1: voxel planes).
    pub fn face_phases(&self, voxels: &VoxelSettings) -> Result<[f32; 2], BenchError> {
        let grid = voxels.grid_for(&self.scene_b, 0.0)?;
        let axis = world_x_axis(&grid);
        let phase_axis = |x: f32| {
            let v = grid.world_to_voxel(Vec3::new(x, 0.5 * ROOM_HEIGHT_M, 0.5 * ROOM_DEPTH_M));
            v[axis].rem_euclid(1.0)
        };
        Ok([
            phase_axis(-0.5 * self.wall_m),
            phase_axis(0.5 * self.wall_m),
        ])
    }
}

/// The scene TOML of one axis-aligned rectangle (the built-in quad turned and scaled): centre
/// `c`, facing `+axis` (`sign` 1) or `-axis`, `size` its extent on the other two axes (in the
/// order x, y, z with `axis` left out).
fn rect(name: &str, c: Vec3, axis: usize, sign: f32, size: [f32; 2]) -> String {
    // The quad lies in the XZ plane facing +Y, 1 m x 1 m; T·R·S with one rotation.
    let (rot, scale) = match (axis, sign > 0.0) {
        (1, true) => ([0.0, 0.0, 0.0], [size[0], 1.0, size[1]]),
        (1, false) => ([180.0, 0.0, 0.0], [size[0], 1.0, size[1]]),
        // About z by -90°: local +y → world +x, local x → world -y.
        (0, true) => ([0.0, 0.0, -90.0], [size[0], 1.0, size[1]]),
        (0, false) => ([0.0, 0.0, 90.0], [size[0], 1.0, size[1]]),
        // About x by 90°: local +y → world +z, local z → world -y.
        (_, true) => ([90.0, 0.0, 0.0], [size[0], 1.0, size[1]]),
        (_, false) => ([-90.0, 0.0, 0.0], [size[0], 1.0, size[1]]),
    };
    format!(
        "\n[[objects]]\nname = \"{name}\"\nbuiltin = \"quad\"\ntranslate = [{}, {}, {}]\n\
         rotate_deg = [{}, {}, {}]\nscale = [{}, {}, {}]\n\
         material = {{ albedo = [0.73, 0.73, 0.73] }}\n",
        c.x, c.y, c.z, rot[0], rot[1], rot[2], scale[0], scale[1], scale[2]
    )
}

/// The six inward-facing walls of the box `[lo, hi]`.
fn room(name: &str, lo: Vec3, hi: Vec3) -> String {
    let c = 0.5 * (lo + hi);
    let s = hi - lo;
    let mut t = String::new();
    for axis in 0..3 {
        // The other two axes' extents, in x, y, z order.
        let size = match axis {
            0 => [s.y, s.z],
            1 => [s.x, s.z],
            _ => [s.x, s.y],
        };
        for (side, sign, at) in [("lo", 1.0, lo[axis]), ("hi", -1.0, hi[axis])] {
            let mut p = c;
            p[axis] = at;
            t += &rect(
                &format!("{name}_{}{side}", ["x", "y", "z"][axis]),
                p,
                axis,
                sign,
                size,
            );
        }
    }
    t
}

/// The scene TOML: the spot light in room A, the camera at `eye` looking at `target`.
fn leak_toml(half_wall_m: f32, width_m: f32, spot: LeakLight, eye: Vec3, target: Vec3) -> String {
    let (h, d) = (ROOM_HEIGHT_M, ROOM_DEPTH_M);
    let b_lo = Vec3::new(half_wall_m, 0.0, 0.0);
    let b_hi = Vec3::new(half_wall_m + width_m, h, d);
    let a_lo = Vec3::new(-half_wall_m - width_m, 0.0, 0.0);
    let a_hi = Vec3::new(-half_wall_m, h, d);
    // (A light shining along the wall's foot reaches room B through the shadow maps' slope
    // bias at walls thinner than a voxel; neither placement does.)
    let (light, dir, cutoff_deg, beam_deg) = spot.spot(a_hi);
    format!(
        "[camera]\nposition = [{}, {}, {}]\ntarget = [{}, {}, {}]\nfov_y_deg = 60.0\n\
         near = 0.01\nfar = 5.0\n\n\
         [[lights]]\nkind = \"spot\"\nposition = [{}, {}, {}]\ndirection = [{}, {}, {}]\n\
         intensity_w_sr = [1.0, 1.0, 1.0]\ncutoff_deg = {cutoff_deg}\nbeam_deg = {beam_deg}\n{}{}",
        eye.x,
        eye.y,
        eye.z,
        target.x,
        target.y,
        target.z,
        light.x,
        light.y,
        light.z,
        dir.x,
        dir.y,
        dir.z,
        room("a", a_lo, a_hi),
        room("b", b_lo, b_hi),
    )
}

/// Room B's camera: in the corner by its outer wall, looking at the dividing wall and the
/// floor before it.
fn camera_b(half_wall_m: f32, width_m: f32) -> (Vec3, Vec3) {
    let (h, d) = (ROOM_HEIGHT_M, ROOM_DEPTH_M);
    let eye = Vec3::new(half_wall_m + 0.92 * width_m, 0.7 * h, 0.95 * d);
    let target = Vec3::new(half_wall_m, 0.3 * h, 0.4 * d);
    (eye, target)
}

/// The voxel-frame axis that is world x (the frame permutes the world axes).
fn world_x_axis(grid: &crate::voxel::VoxelGrid) -> usize {
    let d = grid.dir_world_to_voxel(Vec3::X).abs();
    (0..3).fold(0, |best, i| if d[i] > d[best] { i } else { best })
}

fn mirror_x(p: Vec3) -> Vec3 {
    Vec3::new(-p.x, p.y, p.z)
}

fn build(
    half_wall_m: f32,
    width_m: f32,
    light: LeakLight,
    room_b: bool,
) -> Result<Scene, BenchError> {
    let (eye, target) = camera_b(half_wall_m, width_m);
    let (eye, target) = if room_b {
        (eye, target)
    } else {
        (mirror_x(eye), mirror_x(target))
    };
    let toml = leak_toml(half_wall_m, width_m, light, eye, target);
    let origin = std::path::Path::new("<leak generated scene>");
    Ok(Scene::from_toml_str(
        &toml,
        origin,
        std::path::Path::new("."),
    )?)
}

/// The scene of a wall `wall_voxels` voxels thick for the grid `voxels` puts around it (see
/// the module doc for how the thickness is made exact).
pub fn leak_scene(
    wall_voxels: f32,
    light: LeakLight,
    voxels: &VoxelSettings,
) -> Result<LeakScene, BenchError> {
    if !(wall_voxels.is_finite() && wall_voxels > 0.0 && wall_voxels <= 16.0) {
        return Err(BenchError::LeakWall {
            wall_voxels,
            why: "the thickness must be in (0, 16] voxels",
        });
    }
    // The voxel edge does not depend on the wall or the width (module doc).
    let probe = build(0.0, ROOM_MIN_WIDTH_M, light, true)?;
    let voxel_m = voxels.grid_for(&probe, 0.0)?.voxel_size_m().x;
    let wall_m = wall_voxels * voxel_m;
    // Wanted phase of x = 0 in its voxel: faces at voxel centres for odd whole thicknesses,
    // else x = 0 at a voxel centre.
    let odd_whole = wall_voxels.fract() == 0.0 && (wall_voxels as u32) % 2 == 1;
    let want_phase = if odd_whole { 0.0 } else { 0.5 };
    for step in 0..4 {
        let width_m = ROOM_MIN_WIDTH_M + 0.5 * voxel_m * step as f32;
        let scene_b = build(0.5 * wall_m, width_m, light, true)?;
        let grid = voxels.grid_for(&scene_b, 0.0)?;
        let axis = world_x_axis(&grid);
        let centre = grid.world_to_voxel(Vec3::new(0.0, 0.5 * ROOM_HEIGHT_M, 0.5 * ROOM_DEPTH_M));
        let phase = centre[axis].rem_euclid(1.0);
        let off = (phase - want_phase)
            .abs()
            .min(1.0 - (phase - want_phase).abs());
        if off > 0.05 {
            continue;
        }
        let s = LeakScene {
            scene_a: build(0.5 * wall_m, width_m, light, false)?,
            scene_b,
            wall_voxels,
            light,
            wall_m,
            voxel_m,
            room_b_min: Vec3::new(0.5 * wall_m, 0.0, 0.0),
            room_b_max: Vec3::new(0.5 * wall_m + width_m, ROOM_HEIGHT_M, ROOM_DEPTH_M),
        };
        let phases = s.face_phases(voxels)?;
        let clear = |p: f32| p.min(1.0 - p) >= MIN_FACE_CLEARANCE_VOXELS;
        if phases.iter().all(|&p| clear(p)) {
            return Ok(s);
        }
        return Err(BenchError::LeakWall {
            wall_voxels,
            why: "its faces fall within a fifth of a voxel of a voxel plane; \
                  choose a thickness whose half is not close to a whole or half voxel",
        });
    }
    Err(BenchError::LeakWall {
        wall_voxels,
        why: "no room width puts the wall's centre where its faces clear the voxel planes",
    })
}

/// The methods of the benchmark: hemisphere sampling reading the light maps and reading the
/// radiance volume, the path tracer, VPLs and screen-space GI, at their defaults.
pub fn leak_methods() -> Vec<(String, GiSettings)> {
    let with = |method| GiSettings {
        method,
        ..GiSettings::default()
    };
    vec![
        ("hemisphere".into(), with(GiMethod::Hemisphere)),
        (
            "hemisphere-volume".into(),
            GiSettings {
                radiance_source: RadianceSource::Volume,
                ..with(GiMethod::Hemisphere)
            },
        ),
        ("pathtrace".into(), with(GiMethod::Pathtrace)),
        ("vpl".into(), with(GiMethod::Vpl)),
        ("ssgi".into(), with(GiMethod::Ssgi)),
    ]
}

/// What [`bench_leak`] runs.
#[derive(Clone, Debug)]
pub struct LeakBenchDesc {
    pub walls_voxels: Vec<f32>,
    pub lights: Vec<LeakLight>,
    /// Image width and height, pixels.
    pub size: u32,
    pub methods: Vec<(String, GiSettings)>,
    pub voxels: VoxelSettings,
}

impl Default for LeakBenchDesc {
    fn default() -> Self {
        Self {
            walls_voxels: DEFAULT_WALLS_VOXELS.to_vec(),
            lights: vec![LeakLight::Wall, LeakLight::Floor],
            size: 64,
            methods: leak_methods(),
            voxels: VoxelSettings::default(),
        }
    }
}

/// One method at one wall.
#[derive(Clone, Debug, Serialize)]
pub struct LeakRow {
    pub light: LeakLight,
    pub method: String,
    pub wall_voxels: f32,
    /// Mean indirect radiance in room B's image, W/(m²·sr).
    pub mean_b: f64,
    /// Mean indirect radiance in the mirrored view of room A, W/(m²·sr).
    pub mean_a: f64,
    /// `mean_b / mean_a` (0 when room A shows no indirect light either).
    pub leaked_fraction: f64,
}

/// What [`bench_leak`] measured.
#[derive(Clone, Debug, Serialize)]
pub struct LeakReport {
    pub size: u32,
    pub voxel_m: f32,
    pub rows: Vec<LeakRow>,
}

impl LeakReport {
    /// Leaked fraction per light placement and method (rows) and wall (columns).
    pub fn table(&self) -> String {
        let walls = self.walls();
        let mut s = format!(
            "Light leak: mean indirect radiance in room B / in room A ({}², voxel {:.2} mm; \
             truth 0)\n{:<26}",
            self.size,
            self.voxel_m * 1000.0,
            "light method \\ wall (vox)"
        );
        for w in &walls {
            s += &format!(" {w:>9}");
        }
        s.push('\n');
        let mut keys: Vec<(LeakLight, &str)> = Vec::new();
        for r in &self.rows {
            if !keys.contains(&(r.light, r.method.as_str())) {
                keys.push((r.light, &r.method));
            }
        }
        for (light, m) in keys {
            s += &format!("{:<6}{m:<20}", light_name(light));
            for w in &walls {
                let row = self
                    .rows
                    .iter()
                    .find(|r| r.light == light && r.method == m && r.wall_voxels == *w);
                match row {
                    Some(r) => s += &format!(" {:>9.2e}", r.leaked_fraction),
                    None => s += &format!(" {:>9}", "-"),
                }
            }
            s.push('\n');
        }
        s
    }

    /// `light,method,wall_voxels,mean_b,mean_a,leaked_fraction` lines with a header.
    pub fn csv(&self) -> String {
        let mut s = String::from("light,method,wall_voxels,mean_b,mean_a,leaked_fraction\n");
        for r in &self.rows {
            s += &format!(
                "{},{},{},{:e},{:e},{:e}\n",
                light_name(r.light),
                r.method,
                r.wall_voxels,
                r.mean_b,
                r.mean_a,
                r.leaked_fraction
            );
        }
        s
    }

    fn walls(&self) -> Vec<f32> {
        let mut walls: Vec<f32> = Vec::new();
        for r in &self.rows {
            if !walls.contains(&r.wall_voxels) {
                walls.push(r.wall_voxels);
            }
        }
        walls
    }
}

/// A light placement's name as `--lights` spells it.
fn light_name(l: LeakLight) -> &'static str {
    match l {
        LeakLight::Wall => "wall",
        LeakLight::Floor => "floor",
    }
}

/// Mean over pixels and channels.
pub fn mean_radiance(img: &HdrImage) -> f64 {
    let n = img.data.len().max(1) as f64 * 3.0;
    img.data
        .iter()
        .map(|p| p.iter().map(|&v| f64::from(v)).sum::<f64>())
        .sum::<f64>()
        / n
}

/// The largest channel value of an image.
pub fn max_radiance(img: &HdrImage) -> f32 {
    img.data
        .iter()
        .flat_map(|p| p.iter().copied())
        .fold(0.0, f32::max)
}

/// Renders `scene` at `size`² with `gi` and the benchmark's voxel grid.
pub fn render_leak_view(
    ctx: &Context,
    scene: &Scene,
    size: u32,
    gi: GiSettings,
    voxels: VoxelSettings,
) -> Result<HdrImage, BenchError> {
    let settings = RenderSettings {
        width: size,
        height: size,
        gi,
        voxels: Some(voxels),
        ..RenderSettings::default()
    };
    Ok(render_image(ctx, scene, &settings)?.hdr)
}

/// The direct-only images of room B and of room A; fails unless B's is exactly zero.
pub fn direct_images(
    ctx: &Context,
    s: &LeakScene,
    size: u32,
    voxels: VoxelSettings,
) -> Result<(HdrImage, HdrImage), BenchError> {
    let none = GiSettings::default();
    let b = render_leak_view(ctx, &s.scene_b, size, none, voxels)?;
    let max = max_radiance(&b);
    if max != 0.0 {
        return Err(BenchError::LeakDirect {
            wall_voxels: s.wall_voxels,
            max,
        });
    }
    let a = render_leak_view(ctx, &s.scene_a, size, none, voxels)?;
    Ok((b, a))
}

/// One method's row at one wall, given the direct image of room A.
pub fn leak_row(
    ctx: &Context,
    s: &LeakScene,
    name: &str,
    gi: GiSettings,
    size: u32,
    voxels: VoxelSettings,
    direct_a: &HdrImage,
) -> Result<LeakRow, BenchError> {
    let b = render_leak_view(ctx, &s.scene_b, size, gi, voxels)?;
    let a = render_leak_view(ctx, &s.scene_a, size, gi, voxels)?;
    let mean_b = mean_radiance(&b);
    let mean_a = mean_radiance(&a) - mean_radiance(direct_a);
    Ok(LeakRow {
        light: s.light,
        method: name.to_owned(),
        wall_voxels: s.wall_voxels,
        mean_b,
        mean_a,
        leaked_fraction: if mean_a > 0.0 { mean_b / mean_a } else { 0.0 },
    })
}

/// Every method at every wall; see the module doc.
pub fn bench_leak(ctx: &Context, desc: &LeakBenchDesc) -> Result<LeakReport, BenchError> {
    let mut rows = Vec::new();
    let mut voxel_m = 0.0;
    for (&light, &w) in desc
        .lights
        .iter()
        .flat_map(|l| desc.walls_voxels.iter().map(move |w| (l, w)))
    {
        let s = leak_scene(w, light, &desc.voxels)?;
        voxel_m = s.voxel_m;
        let (_, direct_a) = direct_images(ctx, &s, desc.size, desc.voxels)?;
        for (name, gi) in &desc.methods {
            rows.push(leak_row(
                ctx,
                &s,
                name,
                *gi,
                desc.size,
                desc.voxels,
                &direct_a,
            )?);
        }
    }
    Ok(LeakReport {
        size: desc.size,
        voxel_m,
        rows,
    })
}
