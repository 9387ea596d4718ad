//! Scene-file tests of the GGX and emission keys: TOML material overrides and the MTL PBR
//! extension (`Pr`, `Pm`, `Ke`), and their errors, which name the file and the field.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::*;

const HEAD: &str = "[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
                    [[lights]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = 1.0\n";

fn toml(material: &str) -> Result<Scene, SceneError> {
    let text = format!("{HEAD}[[objects]]\nbuiltin = \"cube\"\nmaterial = {{ {material} }}\n");
    Scene::from_toml_str(&text, Path::new("mat.toml"), Path::new("."))
}

fn the_material(s: &Scene) -> &Material {
    &s.materials[s.objects[0].materials[0]]
}

fn assert_err(r: Result<Scene, SceneError>, parts: &[&str]) {
    let msg = r.expect_err("expected an error").to_string();
    for p in parts {
        assert!(msg.contains(p), "message lacks `{p}`: {msg}");
    }
}

#[test]
fn toml_ggx_and_emission_keys_make_a_ggx_emitter() {
    let s =
        toml("albedo = [0.9, 0.6, 0.3], roughness = 0.4, metallic = 1.0, emission_w_sr_m2 = 2.5")
            .unwrap();
    let m = the_material(&s);
    assert_eq!(
        m.ggx,
        Some(Ggx {
            roughness: 0.4,
            metallic: 1.0
        })
    );
    assert_eq!(m.emission, Vec3::splat(2.5));
    assert!(s.has_ggx() && s.has_emission() && !s.has_phong() && !s.is_all_lambert());
    // Only roughness: a dielectric.
    let s = toml("roughness = 0.5").unwrap();
    assert_eq!(the_material(&s).ggx.map(|g| g.metallic), Some(0.0));
    // Emission alone keeps the material Lambert.
    let s = toml("emission_w_sr_m2 = [0, 1, 2]").unwrap();
    assert!(s.is_all_lambert() && s.has_emission() && !s.has_ggx());
    // Neither: no GGX, no emission.
    let s = toml("albedo = 0.5").unwrap();
    assert!(!s.has_ggx() && !s.has_emission());
}

#[test]
fn bad_toml_ggx_and_emission_values_name_the_file_and_field() {
    assert_err(
        toml("roughness = 1.5"),
        &["mat.toml", "roughness", "outside [0, 1]"],
    );
    assert_err(
        toml("metallic = -0.1"),
        &["mat.toml", "metallic", "outside [0, 1]"],
    );
    assert_err(
        toml("roughness = nan"),
        &["mat.toml", "roughness", "finite"],
    );
    assert_err(
        toml("emission_w_sr_m2 = [1, -1, 0]"),
        &["mat.toml", "emission_w_sr_m2", "negative"],
    );
    assert_err(
        toml("emission_w_sr_m2 = nan"),
        &["mat.toml", "emission_w_sr_m2", "finite"],
    );
    assert_err(
        toml("specular = 0.2, roughness = 0.5"),
        &["mat.toml", "material", "Phong", "GGX"],
    );
}

/// A temp directory with an OBJ triangle using material `a` of `m.mtl` = `mtl`, and a scene
/// loading it; returns the scene path (the directory is left for the OS to clean).
fn obj_scene(tag: &str, mtl: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxgi_mat_{tag}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    std::fs::write(
        dir.join("m.obj"),
        "mtllib m.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, format!("{HEAD}[[objects]]\nmesh = \"m.obj\"\n")).unwrap();
    scene
}

#[test]
fn mtl_pr_pm_ke_are_read() {
    let path = obj_scene(
        "ok",
        "newmtl a\nKd 0.8 0.5 0.2\nPr 0.35\nPm 0.9\nKe 1 2 3\nmap_Pr rough.png\n",
    );
    write_png(&path.parent().unwrap().join("rough.png"), [128; 3]);
    let s = Scene::load(&path).unwrap();
    let m = the_material(&s);
    assert_eq!(
        m.ggx,
        Some(Ggx {
            roughness: 0.35,
            metallic: 0.9
        })
    );
    assert_eq!(
        (m.albedo, m.emission),
        (Vec3::new(0.8, 0.5, 0.2), Vec3::new(1.0, 2.0, 3.0))
    );
    // A Phong override makes the GGX MTL material Phong; an emission override replaces `Ke`.
    let dir = path.parent().unwrap();
    let over = dir.join("over.toml");
    std::fs::write(
        &over,
        format!(
            "{HEAD}[[objects]]\nmesh = \"m.obj\"\n\
             material = {{ specular = 0.3, shininess = 8, emission_w_sr_m2 = 0 }}\n"
        ),
    )
    .unwrap();
    let s = Scene::load(&over).unwrap();
    let m = the_material(&s);
    assert_eq!((m.ggx, m.emission), (None, Vec3::ZERO));
    assert!(s.has_phong() && !s.has_ggx() && !s.has_emission());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_mtl_pr_pm_ke_name_the_file_line_and_key() {
    for (tag, line, parts) in [
        ("pr", "Pr 1.2", &["m.mtl", "line 2", "Pr", "[0, 1]"][..]),
        ("pm", "Pm nan", &["m.mtl", "line 2", "Pm", "[0, 1]"]),
        ("ke", "Ke 1 -2 0", &["m.mtl", "line 2", "Ke", ">= 0"]),
        ("keinf", "Ke 1 inf 0", &["m.mtl", "line 2", "Ke", "finite"]),
    ] {
        let path = obj_scene(tag, &format!("newmtl a\n{line}\n"));
        assert_err(Scene::load(&path), parts);
        let _ = std::fs::remove_dir_all(path.parent().unwrap());
    }
}

#[test]
fn asset_cornell_emissive_is_lit_only_by_its_emitter() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cornell_emissive.toml");
    let s = Scene::load(&path).unwrap();
    assert!(s.lights.is_empty());
    assert!(s.has_emission() && s.has_ggx() && !s.has_phong());
    let sphere = s
        .objects
        .iter()
        .find(|o| o.name == "copper_sphere")
        .unwrap();
    let copper = &s.materials[sphere.materials[0]];
    assert_eq!(copper.ggx.map(|g| g.metallic), Some(1.0));
    // The emitting side of the ceiling patch faces the floor.
    let light = s.objects.iter().find(|o| o.name == "light").unwrap();
    let mesh = &s.meshes[light.mesh];
    let n = light.transform_at(0.0).transform_vector3(mesh.normals[0]);
    assert!(n.y < -0.999, "{n}");
}

/// A PNG of w×h texels all `rgb`, written to `path`.
fn write_png(path: &Path, rgb: [u8; 3]) {
    image::RgbImage::from_pixel(4, 4, image::Rgb(rgb))
        .save(path)
        .unwrap();
}

#[test]
fn mtl_pbr_maps_are_read_and_overrides_drop_them() {
    let path = obj_scene(
        "maps",
        "newmtl a\nKd 0.8 0.5 0.2\nmap_Pr rough.png\nmap_Pm -clamp on metal.png\nmap_Ke glow.png\n",
    );
    let dir = path.parent().unwrap();
    write_png(&dir.join("rough.png"), [128; 3]);
    write_png(&dir.join("metal.png"), [255; 3]);
    write_png(&dir.join("glow.png"), [200, 100, 50]);
    let s = Scene::load(&path).unwrap();
    let m = the_material(&s);
    let maps = m.pbr_maps.as_array().map(|t| t.expect("map loaded"));
    // Roughness and metalness are linear data, emission a color (sRGB).
    let srgb = maps.map(|i| s.textures[i].srgb);
    assert_eq!(srgb, [false, false, true]);
    // Maps alone make the material GGX (the constants' defaults: r 1, m 0); `map_Ke` scales
    // `Ke`, 1 when absent.
    assert_eq!(
        m.ggx,
        Some(Ggx {
            roughness: 1.0,
            metallic: 0.0
        })
    );
    assert_eq!(m.emission, Vec3::ONE);
    assert!(s.has_pbr_maps() && s.has_ggx() && s.has_emission());
    // A TOML constant replaces its map, as `albedo` replaces `map_Kd`.
    let over = dir.join("over.toml");
    std::fs::write(
        &over,
        format!(
            "{HEAD}[[objects]]\nmesh = \"m.obj\"\n\
             material = {{ roughness = 0.3, emission_w_sr_m2 = 2 }}\n"
        ),
    )
    .unwrap();
    let s = Scene::load(&over).unwrap();
    let m = the_material(&s);
    assert_eq!(
        m.pbr_maps.as_array().map(|t| t.is_some()),
        [false, true, false]
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn broken_pbr_maps_name_the_texture_and_key() {
    for key in ["map_Pr", "map_Pm", "map_Ke"] {
        let path = obj_scene(key, &format!("newmtl a\nKd 1 1 1\n{key} bad.png\n"));
        let dir = path.parent().unwrap();
        std::fs::write(dir.join("bad.png"), "not a png").unwrap();
        let bad = dir.join("bad.png").display().to_string();
        assert_err(Scene::load(&path), &[&bad, key, "m.obj"]);
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn missing_pbr_maps_are_errors_naming_mtl_material_key_and_path() {
    for key in ["map_Pr", "map_Pm", "map_Ke"] {
        let path = obj_scene(
            &format!("missing_{key}"),
            &format!("newmtl a\nKd 1 1 1\n{key} -clamp on gone.png\n"),
        );
        let dir = path.parent().unwrap();
        let mtl = dir.join("m.mtl").display().to_string();
        let gone = dir.join("gone.png").display().to_string();
        let err = Scene::load(&path).expect_err("a missing PBR map must fail");
        assert_eq!(err.kind(), "texture-missing");
        let msg = err.to_string();
        for part in [&mtl, "material `a`", key, &gone, "not found"] {
            assert!(msg.contains(part), "message lacks `{part}`: {msg}");
        }
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn packed_roughness_and_metalness_maps_are_errors_naming_mtl_key_and_path() {
    // An occlusion/roughness/metalness texture packs three quantities into r, g, b: reading
    // its first channel as roughness would silently take the occlusion.
    for key in ["map_Pr", "map_Pm"] {
        let path = obj_scene(
            &format!("packed_{key}"),
            &format!("newmtl a\nKd 1 1 1\n{key} orm.png\n"),
        );
        let dir = path.parent().unwrap();
        write_png(&dir.join("orm.png"), [255, 128, 0]);
        let err = Scene::load(&path).expect_err("a packed map must fail");
        assert_eq!(err.kind(), "texture-channels");
        let msg = err.to_string();
        let mtl = dir.join("m.mtl").display().to_string();
        let png = dir.join("orm.png").display().to_string();
        for part in [
            &mtl,
            &png,
            "material `a`",
            key,
            "[255, 128, 0]",
            "grey image",
        ] {
            assert!(msg.contains(part), "message lacks `{part}`: {msg}");
        }
        let _ = std::fs::remove_dir_all(dir);
    }
    // A colored emission map is a color, not packed data.
    let path = obj_scene("colored_ke", "newmtl a\nKd 1 1 1\nmap_Ke glow.png\n");
    let dir = path.parent().unwrap();
    write_png(&dir.join("glow.png"), [255, 128, 0]);
    assert!(Scene::load(&path).is_ok());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn missing_albedo_map_stays_a_warning_but_not_for_a_pbr_map_of_the_same_file() {
    // `map_Kd` keeps the compatibility fallback (the constant `Kd`): OBJ downloads often name
    // textures by paths on their author's machine.
    let path = obj_scene("missing_kd", "newmtl a\nKd 0.3 0.4 0.5\nmap_Kd gone.png\n");
    let dir = path.parent().unwrap();
    let s = Scene::load(&path).unwrap();
    let m = the_material(&s);
    assert_eq!(
        (m.albedo_texture, m.albedo),
        (None, Vec3::new(0.3, 0.4, 0.5))
    );
    // The same missing file as a PBR map after the warning (a cached miss) is still an error.
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl a\nmap_Kd gone.png\nnewmtl b\nmap_Ke gone.png\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\n",
    )
    .unwrap();
    assert_err(Scene::load(&path), &["material `b`", "map_Ke", "gone.png"]);
    let _ = std::fs::remove_dir_all(dir);
}
