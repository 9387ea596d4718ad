//! Every `RenderError` a user can cause, produced from a real input, and released cleanly:
//! each test's context checks at teardown that the failed `Renderer::new` left no object and
//! no GPU memory behind (`common::TestContext`).

mod common;

use voxgi::gi::GiMethod;
use voxgi::light::PointShadow;
use voxgi::render::{RenderError, RenderSettings, Renderer};
use voxgi::scene::{load_scene_arg, Scene};

/// A scene file in a fresh temporary directory, loaded.
fn scene_from(name: &str, text: &str) -> Scene {
    let dir =
        std::env::temp_dir().join(format!("voxgi-render-errors-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).expect("write scene");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let _ = std::fs::remove_dir_all(&dir);
    scene
}

/// A cube lit by `point_lights` point lights.
fn cube_with_point_lights(name: &str, point_lights: usize) -> Scene {
    let mut text =
        String::from("[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n");
    for i in 0..point_lights {
        text += &format!(
            "[[lights]]\nkind = \"point\"\nposition = [{}, 2, 0]\nintensity_w_sr = 1.0\n",
            i as f32 * 0.1
        );
    }
    text += "[[objects]]\nbuiltin = \"cube\"\n";
    scene_from(name, &text)
}

fn small() -> RenderSettings {
    RenderSettings {
        width: 32,
        height: 32,
        ..Default::default()
    }
}

#[test]
fn more_lights_than_the_renderer_holds() {
    let ctx = common::context();
    // MAX_LIGHTS = 64 (render::gpu).
    let scene = cube_with_point_lights("lights", 65);
    let e = Renderer::new(&ctx, &scene, small())
        .err()
        .expect("65 lights refused");
    assert!(matches!(e, RenderError::TooManyLights(65)), "{e}");
    assert!(e.to_string().contains("remove some"), "{e}");
}

#[test]
fn cascades_count_towards_the_shadow_views() {
    let ctx = common::context();
    // 8 directional lights × (1 whole-scene map + 8 cascades) = 72 > MAX_SHADOW_VIEWS = 64;
    // with 7 cascades 64 fit.
    let mut text =
        String::from("[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n");
    for i in 0..8 {
        text += &format!(
            "[[lights]]\nkind = \"directional\"\ndirection = [{}, -1, 0.2]\nirradiance_w_m2 = 0.1\n",
            i as f32 * 0.1
        );
    }
    text += "[[objects]]\nbuiltin = \"cube\"\n";
    let scene = scene_from("suns", &text);
    let mut s = small();
    s.shadow.cascades = 8;
    let e = Renderer::new(&ctx, &scene, s.clone())
        .err()
        .expect("72 views refused");
    assert!(matches!(e, RenderError::TooManyShadowViews(72)), "{e}");
    assert!(e.to_string().contains("--shadow-cascades"), "{e}");
    s.shadow.cascades = 7;
    Renderer::new(&ctx, &scene, s).expect("64 views fit");
}

#[test]
fn more_shadow_views_than_fit_unless_paraboloid() {
    let ctx = common::context();
    // 11 point lights × 6 cube faces = 66 > MAX_SHADOW_VIEWS = 64; as paraboloids 11 × 2 = 22.
    let scene = cube_with_point_lights("views", 11);
    let e = Renderer::new(&ctx, &scene, small())
        .err()
        .expect("66 views refused");
    assert!(matches!(e, RenderError::TooManyShadowViews(66)), "{e}");
    assert!(e.to_string().contains("--point-shadows paraboloid"), "{e}");
    let mut s = small();
    s.shadow.point_technique = PointShadow::DualParaboloid;
    Renderer::new(&ctx, &scene, s).expect("the advice works");
}

#[test]
fn a_scene_without_geometry() {
    let ctx = common::context();
    // Scene files refuse this (no `[[objects]]`); a library caller can still clear them.
    let mut scene = load_scene_arg(None).expect("built-in scene");
    scene.objects.clear();
    let e = Renderer::new(&ctx, &scene, small())
        .err()
        .expect("nothing to draw");
    assert!(matches!(e, RenderError::EmptyScene), "{e}");
}

#[test]
fn sao_without_indirect_light() {
    // SAO multiplies only the indirect light; with --gi none there is none to darken.
    let ctx = common::context();
    let scene = load_scene_arg(None).expect("built-in scene");
    let mut s = small();
    s.gi.method = GiMethod::None;
    s.gi.sao = Some(voxgi::gi::SaoSettings::default());
    let e = Renderer::new(&ctx, &scene, s).err().expect("refused");
    assert!(matches!(e, RenderError::SaoWithoutGi), "{e}");
    assert!(e.to_string().contains("--gi"), "{e}");
}

#[test]
fn settings_out_of_range_name_their_flag() {
    let ctx = common::context();
    let scene = load_scene_arg(None).expect("built-in scene");
    let mut s = small();
    s.width = 0;
    let e = Renderer::new(&ctx, &scene, s)
        .err()
        .expect("width 0 refused");
    assert!(
        matches!(&e, RenderError::Settings(l) if l.name == "--width"),
        "{e}"
    );
    let mut s = small();
    s.gi.rays = 0;
    let e = Renderer::new(&ctx, &scene, s)
        .err()
        .expect("0 rays refused");
    assert!(e.to_string().contains("--gi-rays = 0"), "{e}");
}

#[test]
fn a_voxel_error_after_the_grid_is_built_releases_the_frame() {
    let ctx = common::context();
    let scene = load_scene_arg(None).expect("built-in scene");
    // The default 128² grid has hierarchy levels 0..=7: level 12 fails in the debug pass,
    // after the scene, the passes and the voxel grid were created.
    let s = RenderSettings {
        debug: Some(voxgi::voxel::debug_view::DebugSettings {
            view: voxgi::voxel::debug_view::DebugView::Level,
            level: 12,
            ..Default::default()
        }),
        ..small()
    };
    let e = Renderer::new(&ctx, &scene, s)
        .err()
        .expect("level 12 refused");
    assert!(matches!(e, RenderError::Voxel(_)), "{e}");
    assert!(e.to_string().contains("--debug-level"), "{e}");
}

#[test]
fn a_voxel_grid_larger_than_the_device_memory_is_refused_before_allocating() {
    let ctx = common::context();
    let scene = load_scene_arg(None).expect("built-in scene");
    // 16384² columns × 64 layers × 16 B is 256 GiB for the image's mip 0 alone: more than
    // any device heap (lavapipe reports a few GiB).
    let s = RenderSettings {
        voxels: Some(voxgi::voxel::gpu::VoxelSettings {
            max_res_xy: 16384,
            layers: 64,
            ..Default::default()
        }),
        ..small()
    };
    let e = Renderer::new(&ctx, &scene, s).err().expect("too large");
    assert!(
        matches!(&e, RenderError::OutOfDeviceMemory(m)
            if m.need_bytes > m.available_bytes && m.subject.contains("64 layer")),
        "{e}"
    );
    assert!(
        e.to_string().contains("--voxels") && e.to_string().contains("GiB"),
        "{e}"
    );
}

/// Asserts that `e` is a memory error of `flags` needing more than is available.
fn assert_out_of_memory(e: &RenderError, flags: &str) {
    assert!(
        matches!(e, RenderError::OutOfDeviceMemory(m)
            if m.need_bytes > m.available_bytes && m.flags == flags),
        "{e}"
    );
    let text = e.to_string();
    assert!(text.contains(flags) && text.contains("GiB"), "{text}");
}

#[test]
fn a_frame_larger_than_the_device_allows_is_refused_before_allocating() {
    let ctx = common::context();
    let scene = load_scene_arg(None).expect("built-in scene");
    let max_one = ctx
        .info
        .max_memory_allocation_bytes
        .min(ctx.info.max_buffer_bytes);
    // 16384² RGBA32F read-back is 16384² × 16 B = 4 GiB in one buffer; any device that
    // offers more would still be refused by the heap sum, so only the kind of limit varies.
    let big = RenderSettings {
        width: 16384,
        height: 16384,
        ..Default::default()
    };
    let e = Renderer::new(&ctx, &scene, big)
        .err()
        .expect("16384² refused");
    assert_out_of_memory(&e, "--width/--height");
    if max_one < 16384 * 16384 * 16 {
        assert!(e.to_string().contains("`readback hdr`"), "{e}");
    }
    // A normal size still builds on the same context after the refusal.
    Renderer::new(&ctx, &scene, small()).expect("32² renders");
}

#[test]
fn transient_arenas_are_counted_before_the_executor_allocates() {
    let ctx = common::context();
    let scene = load_scene_arg(None).expect("built-in scene");
    // The read-back buffer fits one allocation when w·h·16 ≤ max, but the G-buffer arena
    // (albedo + normal RGBA16F, depth D32, direct radiance RGBA32F alive together: at least
    // 8 + 8 + 4 + 16 = 36 B per pixel) does not when w·h·36 > max. The smallest square
    // past max/36 keeps the read-back (the one allocation made before the check) small.
    let max_one = ctx
        .info
        .max_memory_allocation_bytes
        .min(ctx.info.max_buffer_bytes);
    let side = ((max_one / 36) as f64).sqrt() as u32 + 1;
    let pixels = u64::from(side) * u64::from(side);
    if side > voxgi::limits::WIDTH.max || pixels * 16 > max_one {
        eprintln!("skipped: this device allocates {max_one} B at once, more than a {side}² arena");
        return;
    }
    let s = RenderSettings {
        width: side,
        height: side,
        gi: voxgi::gi::GiSettings {
            method: GiMethod::None,
            ..Default::default()
        },
        ..Default::default()
    };
    let e = Renderer::new(&ctx, &scene, s).err().expect("refused");
    assert_out_of_memory(&e, "--width/--height");
    assert!(e.to_string().contains("graph arena"), "{e}");
}

#[test]
fn resources_beyond_what_is_left_of_the_heap_are_refused() {
    use voxgi::render::memory::{check_fits, MemoryLimit, MemoryNeed};
    let ctx = common::context();
    let need = |bytes| MemoryNeed {
        name: "probe".into(),
        bytes,
        is_buffer: false,
    };
    let heap = ctx.info.device_local_heap_bytes;
    // Exactly the one-allocation limit fits; one byte more does not.
    let max_one = ctx.info.max_memory_allocation_bytes.min(heap);
    check_fits(&ctx, "probe", "--width/--height", &[need(max_one)], 0).expect("at the limit");
    let e = check_fits(&ctx, "probe", "--width/--height", &[need(max_one + 1)], 0)
        .expect_err("over the limit");
    assert_out_of_memory(&e, "--width/--height");
    // With all but 1 KiB of the heap already taken, 2 KiB no longer fit.
    let e =
        check_fits(&ctx, "probe", "--voxels", &[need(2048)], heap - 1024).expect_err("heap full");
    assert!(
        matches!(&e, RenderError::OutOfDeviceMemory(m)
            if m.limit == MemoryLimit::Heap && m.need_bytes == 2048 && m.available_bytes == 1024),
        "{e}"
    );
    // What is held already is named with what sizes it, since lowering the subject's own
    // flag cannot free it.
    let text = e.to_string();
    assert!(
        text.contains("held already")
            && text.contains("--voxels")
            && text.contains("--shadow-resolution"),
        "{text}"
    );
}

/// What the viewer asks before it resizes to a window (`Renderer::check_frame_size`): a size
/// whose frame cannot fit is refused before anything of it exists, naming the allocation;
/// the renderer is left as it was, and a size that fits passes, extra needs included.
#[test]
fn a_resize_past_the_device_memory_is_refused_before_allocating() {
    use voxgi::render::memory::MemoryNeed;
    let ctx = common::context();
    let scene = load_scene_arg(None).expect("built-in scene");
    let mut r = Renderer::new(&ctx, &scene, small()).expect("32² renders");
    let held = ctx.allocated_bytes();
    // 16000² RGBA32F read-back: 16000² × 16 B = 3.8 GiB in one buffer, past lavapipe's
    // 2 GiB maxMemoryAllocationSize; any device that allocates that much at once still
    // fails the heap sum with the transients (at least 36 B per pixel per frame in flight).
    let e = r
        .check_frame_size(&ctx, &scene, (16000, 16000), &[])
        .expect_err("16000² refused");
    assert!(
        matches!(&e, RenderError::OutOfDeviceMemory(m)
            if m.need_bytes > m.available_bytes && m.subject.contains("16000×16000")),
        "{e}"
    );
    assert_eq!(ctx.allocated_bytes(), held, "the check allocated");
    assert_eq!((r.settings.width, r.settings.height), (32, 32));
    r.check_frame_size(&ctx, &scene, (64, 48), &[])
        .expect("64×48 fits");
    // What the caller adds counts: one more byte than the heap holds is refused.
    let heap = MemoryNeed {
        name: "probe".into(),
        bytes: ctx.info.device_local_heap_bytes + 1,
        is_buffer: false,
    };
    let e = r
        .check_frame_size(&ctx, &scene, (64, 48), &[heap])
        .expect_err("the extra need refused");
    assert!(
        matches!(&e, RenderError::OutOfDeviceMemory(m) if m.need_bytes > m.available_bytes),
        "{e}"
    );
}
