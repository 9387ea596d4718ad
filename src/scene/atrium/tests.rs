//! The generator's geometry without a GPU: counts, closed solids, degenerate triangles,
//! determinism and the committed scene file.

use super::*;
use std::collections::HashMap;

/// Built once per test binary run would need a lazy static; building takes well under a
/// second, so each test builds its own.
fn model() -> AtriumModel {
    build()
}

#[test]
fn triangle_count_is_sponza_scale() {
    // Sponza has about 262 000 triangles; "a few hundred thousand" is the brief.
    let n = model().faces.len();
    assert!((200_000..=500_000).contains(&n), "{n} triangles");
}

#[test]
fn closed_solids_are_watertight_and_wound_outward() {
    let m = model();
    // Directed edges (position indices) per closed solid: a closed, consistently wound
    // (2-manifold) surface has every edge exactly once in each direction.
    let mut edges: HashMap<(u32, u32, u32), u32> = HashMap::new();
    for f in m.faces.iter().filter(|f| m.solid_closed[f.solid as usize]) {
        for k in 0..3 {
            let (a, b) = (f.corners[k][0], f.corners[(k + 1) % 3][0]);
            *edges.entry((f.solid, a, b)).or_default() += 1;
        }
    }
    for (&(solid, a, b), &count) in &edges {
        assert_eq!(count, 1, "solid {solid}: edge {a}->{b} used {count} times");
        assert_eq!(
            edges.get(&(solid, b, a)),
            Some(&1),
            "solid {solid}: edge {a}->{b} has no opposite edge (a hole or a flipped face)"
        );
    }
    // Per storey: 24 columns on the perimeter of a 12 m x 24 m courtyard with 3 m bays
    // (2 x 9 on the long sides, 2 x 3 between the corners), 5 solids each, and 2 x 8 + 2 x 4
    // arch bays; plus the ground slab, 4 walls and 2 x 4 gallery and roof slabs.
    let closed = m.solid_closed.iter().filter(|&&c| c).count();
    assert_eq!(closed, 2 * (24 * 5 + 24) + 1 + 4 + 8);
    for solid in (0..m.solid_closed.len() as u32).filter(|&s| m.solid_closed[s as usize]) {
        assert!(
            m.signed_volume_m3(solid) > 0.0,
            "solid {solid} is wound inward"
        );
    }
}

#[test]
fn every_solid_closed_except_the_banner_sheets() {
    let m = model();
    let open: Vec<u32> = (0..m.solid_closed.len() as u32)
        .filter(|&s| !m.solid_closed[s as usize])
        .collect();
    // 8 banners, two sheets each; all their faces are cloth.
    assert_eq!(open.len(), 16);
    for f in m.faces.iter().filter(|f| open.contains(&f.solid)) {
        assert!(matches!(
            f.material,
            AtriumMaterial::ClothRed | AtriumMaterial::ClothBlue
        ));
    }
}

#[test]
fn no_degenerate_triangles_and_unit_normals() {
    let m = model();
    // The smallest intended triangle: a cap wedge of the thinnest lathe, radius >= 0.15 m
    // and 48 segments: area = r^2 sin(2 pi / 48) / 2 >= 1.5e-3 m^2; the arch bay's crown
    // strips are 2 r sin(pi / 96) wide, about 0.08 m x 0.1 m. A bound of 1e-5 m^2 is far
    // below every intended face and far above rounding noise.
    for (i, f) in m.faces.iter().enumerate() {
        let [a, b, c] = f.corners.map(|k| m.positions[k[0] as usize]);
        let area = (b - a).cross(c - a).length() / 2.0;
        assert!(area > 1e-5, "face {i} has area {area} m^2");
    }
    for n in &m.normals {
        assert!(
            (n.length() - 1.0).abs() < 1e-4 && n.is_finite(),
            "normal {n}"
        );
    }
    assert!(m.uvs.iter().all(|t| t.is_finite()));
}

#[test]
fn the_geometry_stays_inside_the_walls() {
    let m = model();
    let lo = Vec3::new(
        -WALL_HALF_X_M - WALL_THICK_M,
        -SLAB_THICK_M,
        -WALL_HALF_Z_M - WALL_THICK_M,
    );
    let hi = Vec3::new(
        WALL_HALF_X_M + WALL_THICK_M,
        STOREYS[1].top_y_m + SLAB_THICK_M,
        WALL_HALF_Z_M + WALL_THICK_M,
    );
    for p in &m.positions {
        assert!(
            p.cmpge(lo - 1e-4).all() && p.cmple(hi + 1e-4).all(),
            "{p} outside the building"
        );
    }
}

#[test]
fn generator_is_deterministic() {
    let dir = std::env::temp_dir().join(format!("voxgi-atrium-det-{}", std::process::id()));
    let (a, b) = (dir.join("a"), dir.join("b"));
    let na = write(&a).expect("writes");
    let nb = write(&b).expect("writes");
    assert_eq!(na, nb);
    for name in FILES {
        let (x, y) = (
            std::fs::read(a.join(name)).unwrap(),
            std::fs::read(b.join(name)).unwrap(),
        );
        assert!(!x.is_empty(), "{name} is empty");
        assert!(x == y, "{name} differs between two runs");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn committed_scene_file_is_the_generated_one() {
    let committed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/scenes/atrium.toml"
    ))
    .expect("assets/scenes/atrium.toml");
    assert_eq!(committed, scene_toml("../generated/atrium/atrium.obj"));
}

#[test]
fn kd_is_the_texture_mean() {
    // The MTL's Kd is the mean of the texture the renderer samples: decode the 8-bit sRGB
    // texture back to linear and average all texels; the 8-bit rounding (half a step, at
    // most 0.0075 in linear below 0.9) is all that separates them.
    for material in AtriumMaterial::ALL {
        let img = texture(material);
        let srgb_to_linear = |c: u8| {
            let s = c as f32 / 255.0;
            if s <= 0.04045 {
                s / 12.92
            } else {
                ((s + 0.055) / 1.055).powf(2.4)
            }
        };
        let sum: Vec3 = img
            .pixels()
            .map(|p| Vec3::from_array(p.0.map(srgb_to_linear)))
            .sum();
        let mean = sum / (img.width() * img.height()) as f32;
        let kd = material.mean_albedo();
        assert!(
            (mean - kd).abs().max_element() < 0.02,
            "{material:?}: texture mean {mean}, Kd {kd}"
        );
        assert!(
            kd.max_element() < 0.9,
            "{material:?}: albedo {kd} too bright"
        );
    }
}
