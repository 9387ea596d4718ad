//! The generated scenes the benchmarks run on.

use super::BenchError;
use crate::scene::Scene;
use glam::Vec3;

/// The scene rows' scenes: Cornell, bunny-in-box and [`dense_scene`].
pub fn bench_scenes() -> Result<Vec<(String, Scene)>, BenchError> {
    // From the current directory, else the project's root (the binary may run elsewhere,
    // e.g. a release build carried to another machine).
    let scenes_dir = crate::assets::find(std::path::Path::new("assets/scenes"));
    Ok(vec![
        ("cornell".into(), crate::scene::load_scene_arg(None)?),
        (
            "bunny-in-box".into(),
            Scene::load(scenes_dir.join("cornell_bunny.toml"))?,
        ),
        ("dense-bunnies".into(), dense_scene(&scenes_dir)?),
    ])
}

/// The generated scenes' frame: the Cornell walls, the default camera and a spot light under
/// the ceiling aimed down; objects are appended to it.
pub const CORNELL_SPOT_TOML: &str =
    "[camera]\nposition = [0.278, 0.273, -0.800]\ntarget = [0.278, 0.273, 0.0]\n\
     fov_y_deg = 39.3\nnear = 0.01\nfar = 10.0\n\n\
     [[lights]]\nkind = \"spot\"\nposition = [0.278, 0.540, 0.2796]\n\
     direction = [0.0, -1.0, 0.0]\nintensity_w_sr = [1.0, 1.0, 1.0]\n\
     cutoff_deg = 50.0\nbeam_deg = 40.0\n\n\
     [[objects]]\nname = \"walls\"\nbuiltin = \"cornell_walls\"\n";

/// Bunnies per axis of [`dense_scene`].
pub const DENSE_BUNNIES_PER_AXIS: u32 = 4;

/// The dense generated scene: the Cornell walls around a 4×4×4 grid of Stanford bunnies
/// (64 instances of `assets/meshes/bunny.obj`, 3,674 triangles each, 0.1 m tall; 235,146
/// triangles with the walls), one per cell of the box's interior, each turned a further 30°
/// about y than the previous so that neighbours differ. Deterministic; `scenes_dir` resolves
/// the mesh path. The instances share one atlas, so the atlas voxelizer packs it once and
/// splats its points 64 times.
pub fn dense_scene(scenes_dir: &std::path::Path) -> Result<Scene, BenchError> {
    let n = DENSE_BUNNIES_PER_AXIS;
    // bunny.obj spans x [-4.96, 4.95], y [0, 9.65], z [-3.73, 3.81] (cornell_bunny.toml):
    // within 6.26 of its vertical axis, so at any turn it stays inside its cell.
    let cell_m = 0.54 / n as f32;
    let scale = 0.95 * 0.5 * cell_m / 6.26;
    let mut toml = String::from(CORNELL_SPOT_TOML);
    let mut k = 0;
    for j in 0..n {
        for i in 0..n {
            for l in 0..n {
                let x = 0.005 + (i as f32 + 0.5) * cell_m;
                // A millimetre up: the mesh's base dips just below y = 0.
                let y = 0.001 + j as f32 * cell_m;
                let z = 0.01 + (l as f32 + 0.5) * cell_m;
                toml += &format!(
                    "\n[[objects]]\nname = \"bunny_{k}\"\nmesh = \"../meshes/bunny.obj\"\n\
                     translate = [{x}, {y}, {z}]\nrotate_deg = [0.0, {}, 0.0]\n\
                     scale = {scale}\nmaterial = {{ albedo = [0.73, 0.73, 0.73] }}\n",
                    (30 * k) % 360
                );
                k += 1;
            }
        }
    }
    Ok(Scene::from_toml_str(
        &toml,
        std::path::Path::new("<dense generated scene>"),
        scenes_dir,
    )?)
}

/// A cube of edge 0.8 inside the unit box, each face split into `n`×`n` quads (12·n²
/// triangles): the same surface at any `n`.
pub fn tessellated_cube(n: u32) -> (Vec<Vec3>, Vec<u32>) {
    let n = n.max(1);
    let (mut pos, mut idx) = (Vec::new(), Vec::new());
    for axis in 0..3 {
        for side in [0.0f32, 1.0] {
            let base = pos.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                    let mut p = [0.0; 3];
                    p[axis] = side;
                    p[(axis + 1) % 3] = u;
                    p[(axis + 2) % 3] = v;
                    pos.push(Vec3::from(p) * 0.8 + 0.1);
                }
            }
            for j in 0..n {
                for i in 0..n {
                    let a = base + j * (n + 1) + i;
                    idx.extend([a, a + 1, a + n + 1, a + 1, a + n + 2, a + n + 1]);
                }
            }
        }
    }
    (pos, idx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::gpu::scene_triangles;

    #[test]
    fn the_dense_scene_fills_the_box_with_disjoint_bunnies() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
        let s = dense_scene(&dir).expect("the dense scene builds");
        let n = DENSE_BUNNIES_PER_AXIS.pow(3) as usize;
        assert_eq!(s.objects.len(), n + 1, "walls and the bunnies");
        // Tight bounds of each object's transformed vertices.
        let bounds = |o: &crate::scene::Object| {
            let m = o.transform_at(0.0);
            let mesh = &s.meshes[o.mesh];
            mesh.positions
                .iter()
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                    let p = m.transform_point3(p);
                    (lo.min(p), hi.max(p))
                })
        };
        let walls = bounds(&s.objects[0]);
        let boxes: Vec<_> = s.objects[1..].iter().map(bounds).collect();
        for b in &boxes {
            assert!(
                b.0.cmpge(walls.0).all() && b.1.cmple(walls.1).all(),
                "{b:?}"
            );
        }
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                let overlap = a.0.cmplt(b.1).all() && b.0.cmplt(a.1).all();
                assert!(!overlap, "{a:?} overlaps {b:?}");
            }
        }
        let tris =
            |s: &Scene| scene_triangles(s, 0.0, false).len() + scene_triangles(s, 0.0, true).len();
        assert_eq!(tris(&s), 235_146);
        let again = dense_scene(&dir).expect("builds again");
        assert_eq!(
            scene_triangles(&again, 0.0, false),
            scene_triangles(&s, 0.0, false),
            "deterministic"
        );
    }

    #[test]
    fn tessellated_cubes_share_one_surface() {
        let area = |n: u32| {
            let (p, idx) = tessellated_cube(n);
            idx.chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [0, 1, 2].map(|k| p[t[k] as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum::<f32>()
        };
        assert_eq!(
            tessellated_cube(4).1.len() / 3,
            16 * tessellated_cube(1).1.len() / 3
        );
        assert!((area(1) - 6.0 * 0.64).abs() < 1e-4);
        assert!((area(4) - area(1)).abs() < 1e-4);
    }
}
