//! The light-leak benchmark's scenes (`voxgi bench leak`): both rooms are closed, the wall is
//! exactly its thickness in voxels, room B gets no direct light, and one exact statement:
//! hemisphere sampling from the light maps shows exactly no light in room B at any wall, the
//! thinnest included; the path tracer's bounces no longer leak through a half-voxel wall; and
//! neither does the radiance volume, at the thinnest or the thickest wall.
//! Validation on.

mod common;

use glam::Vec3;
use voxgi::bench::{
    direct_images, leak_methods, leak_row, leak_scene, max_radiance, LeakLight, LeakScene,
    DEFAULT_WALLS_VOXELS,
};
use voxgi::voxel::gpu::{scene_triangles, VoxelSettings};

/// Area of a triangle.
fn area(t: &[Vec3; 3]) -> f32 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// Room B is closed: each of the six faces of its box is covered by triangles lying in that
/// face, whose areas add up to the face's area (the quads do not overlap), with normals
/// pointing into the room; and no triangle reaches into the room's open interior.
fn assert_room_b_closed(s: &LeakScene) {
    let tris = scene_triangles(&s.scene_b, 0.0, false);
    let (lo, hi) = (s.room_b_min, s.room_b_max);
    let eps = 1e-5;
    for axis in 0..3 {
        for (at, inward) in [(lo[axis], 1.0f32), (hi[axis], -1.0)] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut covered = 0.0;
            for t in &tris {
                let in_plane = t.iter().all(|p| (p[axis] - at).abs() < eps);
                let in_face = t.iter().all(|p| {
                    p[u] > lo[u] - eps
                        && p[u] < hi[u] + eps
                        && p[v] > lo[v] - eps
                        && p[v] < hi[v] + eps
                });
                if in_plane && in_face {
                    let n = (t[1] - t[0]).cross(t[2] - t[0]);
                    assert!(
                        n[axis] * inward > 0.0,
                        "face {axis}@{at}: normal {n} points out"
                    );
                    covered += area(t);
                }
            }
            let face = (hi[u] - lo[u]) * (hi[v] - lo[v]);
            assert!(
                (covered - face).abs() < 1e-4 * face,
                "wall {}: face {axis}@{at} covered {covered} of {face} m²",
                s.wall_voxels
            );
        }
    }
    for t in &tris {
        // A triangle strictly inside the box would be clutter or a crack-filling piece; a
        // triangle crossing it would be an opening's edge. Its centroid must lie outside the
        // open box or on its boundary.
        let c = (t[0] + t[1] + t[2]) / 3.0;
        let inside = (0..3).all(|a| c[a] > lo[a] + eps && c[a] < hi[a] - eps);
        assert!(!inside, "a triangle inside room B: {t:?}");
    }
}

#[test]
fn walls_are_exact_in_voxels_and_the_rooms_closed() {
    let voxels = VoxelSettings::default();
    for &w in &DEFAULT_WALLS_VOXELS {
        let s = leak_scene(w, LeakLight::Wall, &voxels).expect("the scene builds");
        assert!((s.wall_m - w * s.voxel_m).abs() <= 1e-6 * s.voxel_m);
        let [a, b] = s.face_phases(&voxels).expect("grid");
        // Faces inside their voxels, clear of the planes; a whole t voxels apart (phases
        // equal for whole t; for t < 1 both faces in one voxel, b − a = t).
        for p in [a, b] {
            assert!(p.min(1.0 - p) >= 0.2, "wall {w}: face phase {p}");
        }
        let expected = (b - a).rem_euclid(1.0);
        assert!(
            (expected - w.fract()).abs() < 1e-3,
            "wall {w}: faces at phases {a}, {b}"
        );
        assert_room_b_closed(&s);
    }
    assert!(leak_scene(0.0, LeakLight::Wall, &voxels).is_err());
    assert!(leak_scene(f32::NAN, LeakLight::Wall, &voxels).is_err());
}

/// Room B's direct image is exactly zero at the thinnest and the thickest wall (the wall
/// spot's cone reaches room B only through the wall's middle, 8 cm and more behind its
/// occluder in the shadow map; the floor spot's cone holds no point of room B), while room
/// A's is not.
#[test]
fn room_b_gets_no_direct_light() {
    let ctx = common::context();
    let voxels = VoxelSettings::default();
    for (w, light) in [
        (0.25, LeakLight::Wall),
        (4.0, LeakLight::Wall),
        (0.25, LeakLight::Floor),
    ] {
        let s = leak_scene(w, light, &voxels).expect("scene");
        let (b, a) = direct_images(&ctx, &s, 32, voxels).expect("room B is dark");
        assert_eq!(max_radiance(&b), 0.0);
        assert!(
            max_radiance(&a) > 0.1,
            "room A is lit: {}",
            max_radiance(&a)
        );
    }
}

/// Hemisphere sampling from the reflective light maps leaks exactly nothing, even through a
/// quarter-voxel wall. Why it is exact: the spot's cone meets room A only in a disk on the
/// dividing wall's A face (normal −x), so the light maps hold no other lit surface. Every
/// ray origin lies in room B (x > 0: G-buffer points of room B moved along their inward
/// normals, no offset along the ray by default). A hit that the light-map lookup accepts
/// must lie within the tolerance (1.5 voxel diagonals plus a texel) of the disk and see its
/// front: dot(n, −d) > 0 with n = −x, i.e. d.x > 0 — the ray moves away from the wall, so
/// its hit lies at x ≥ its origin's and can come near the disk only where room B's own
/// surfaces stand in front of it (the wall's B face, which the origin already left by the
/// normal offset of a voxel diagonal). So no ray gathers light: B's image is 0.0 exactly,
/// while room A's mirrored view gathers light (> 0), so the ratio is a measured 0.
#[test]
fn hemisphere_from_light_maps_leaks_nothing_through_the_thinnest_wall() {
    let ctx = common::context();
    let voxels = VoxelSettings::default();
    let s = leak_scene(0.25, LeakLight::Wall, &voxels).expect("scene");
    let (_, direct_a) = direct_images(&ctx, &s, 32, voxels).expect("room B dark");
    let (name, gi) = leak_methods()
        .into_iter()
        .find(|(n, _)| n == "hemisphere")
        .expect("listed");
    let row = leak_row(&ctx, &s, &name, gi, 32, voxels, &direct_a).expect("renders");
    assert!(row.mean_a > 1e-4, "room A gathers light: {row:?}");
    assert_eq!(row.mean_b, 0.0, "{row:?}");
    assert_eq!(row.leaked_fraction, 0.0);
}

/// The path tracer's later bounces start back along the ray that found their hit, not off
/// the hit voxel along its normal. With room A's floor lit from beside a half-voxel wall, the
/// normal offset (one voxel diagonal, 14 mm, against a 4 mm wall) carried second-bounce
/// origins from room B's floor into room A (leaked fraction 4.2e-4 before the change); an
/// origin on the traversed, empty part of a ray from room B cannot be behind the wall, whose
/// faces mark every voxel of its plane, so no path from B reaches room A's lit floor and B's
/// image is exactly 0, while room A's mirrored view gathers light.
#[test]
fn path_tracer_bounces_do_not_leak_through_a_half_voxel_wall() {
    let ctx = common::context();
    let voxels = VoxelSettings::default();
    let s = leak_scene(0.5, LeakLight::Floor, &voxels).expect("scene");
    let (_, direct_a) = direct_images(&ctx, &s, 32, voxels).expect("room B dark");
    let (name, gi) = leak_methods()
        .into_iter()
        .find(|(n, _)| n == "pathtrace")
        .expect("listed");
    let row = leak_row(&ctx, &s, &name, gi, 32, voxels, &direct_a).expect("renders");
    assert!(row.mean_a > 1e-3, "room A gathers light: {row:?}");
    assert_eq!(row.mean_b, 0.0, "{row:?}");
}

/// The radiance volume (`--gi-radiance volume`) leaks exactly nothing through the thinnest
/// and the thickest wall. Before shadow-map taps past the map's edge took the edge texel
/// (they counted as lit) it leaked 1.5e-4 (quarter-voxel wall) and 7.3e-5 (4 voxels): the
/// lit voxels were room B's far wall at the rim of the spot's 30° cone, where the volume's
/// lookup point (a voxel diagonal off the voxel's centre toward the light) and the PCF kernel
/// reach past the edge of the spot's map. Why 0 is exact now: the map's square frustum
/// (±30° on both axes) meets the wall plane 0.35 m ahead within 0.35·tan 30° = 0.202 m of the
/// spot's axis (y = 0.25, z = 0.5 m) in y and z, inside the wall's A face (0.5 × 1 m), so every
/// texel, hence every clamped tap, holds that face. Each voxel of room B in the cone is looked
/// up from a point in room B or inside the wall: at the thick wall ≥ 4 − 1 − √3 > 1 voxel
/// (8 mm) behind the A face, against a depth bias of a few texels of about 1 mm (1024² map,
/// ≤ 0.8 m away). At the quarter-voxel wall the one voxel holding both faces is lit on its A
/// side only, which a ray from room B (arriving from +x) sees from behind and rejects. Room A's
/// mirrored view gathers light (> 0).
#[test]
fn radiance_volume_leaks_nothing_through_thin_or_thick_walls() {
    let ctx = common::context();
    let voxels = VoxelSettings::default();
    let (name, gi) = leak_methods()
        .into_iter()
        .find(|(n, _)| n == "hemisphere-volume")
        .expect("listed");
    for w in [0.25, 4.0] {
        let s = leak_scene(w, LeakLight::Wall, &voxels).expect("scene");
        let (_, direct_a) = direct_images(&ctx, &s, 32, voxels).expect("room B dark");
        let row = leak_row(&ctx, &s, &name, gi, 32, voxels, &direct_a).expect("renders");
        assert!(row.mean_a > 1e-4, "room A gathers light: {row:?}");
        assert_eq!(row.mean_b, 0.0, "wall {w}: {row:?}");
    }
}
