//! The command line refuses bad values with an error naming the flag, and a command that fails
//! after the device is up releases everything: no gpu-allocator leak report, no validation
//! message at teardown.

mod common;

use common::voxgi;

/// Runs `render` (at 32² unless `extra` gives a size) with `extra`, expects failure and
/// returns stderr.
fn render_fails(extra: &[&str]) -> String {
    let out_png = std::env::temp_dir().join(format!("voxgi-cli-errors-{}.png", std::process::id()));
    let out_png = out_png.to_string_lossy().into_owned();
    let mut args = vec!["render", "-o", &out_png];
    for flag in ["--width", "--height"] {
        if !extra.contains(&flag) {
            args.extend([flag, "32"]);
        }
    }
    args.extend_from_slice(extra);
    let out = voxgi(&args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{extra:?} succeeded:\n{stderr}");
    stderr
}

#[test]
fn every_flag_out_of_range_is_refused_naming_the_flag() {
    // One value past an end of each range of `voxgi::limits` (NaN for the real-valued ones).
    let cases: &[(&[&str], &str)] = &[
        (&["--width", "20000"], "--width = 20000"),
        (&["--height", "0"], "--height = 0"),
        (&["--time", "nan"], "--time = NaN"),
        (&["--exposure", "nan"], "--exposure = NaN"),
        (&["--exposure", "0"], "--exposure = 0"),
        (&["--shadow-resolution", "8"], "--shadow-resolution = 8"),
        (&["--pcf-radius", "9"], "--pcf-radius = 9"),
        (&["--shadow-cascades", "0"], "--shadow-cascades = 0"),
        (&["--shadow-cascades", "9"], "--shadow-cascades = 9"),
        (
            &["--shadow-cascade-lambda", "1.5"],
            "--shadow-cascade-lambda = 1.5",
        ),
        (&["--voxels", "0"], "--voxels = 0"),
        (&["--voxels", "100000"], "--voxels = 100000"),
        (&["--voxel-layers", "0"], "--voxel-layers = 0"),
        (&["--gi-rays", "0"], "--gi-rays = 0"),
        (&["--gi-radius", "nan"], "--gi-radius = NaN"),
        (&["--gi-normal-offset=-1"], "--gi-normal-offset = -1"),
        (&["--gi-ray-offset", "inf"], "--gi-ray-offset = inf"),
        (&["--gi-filter-radius", "65"], "--gi-filter-radius = 65"),
        (&["--gi-filter-passes", "17"], "--gi-filter-passes = 17"),
        (&["--gi-frames", "0"], "--gi-frames = 0"),
        (
            &["--light-map-resolution", "8"],
            "--light-map-resolution = 8",
        ),
        (&["--gi-start-level", "15"], "--gi-start-level = 15"),
        (&["--gi-max-iterations", "0"], "--gi-max-iterations = 0"),
        (
            &["--debug", "level", "--debug-level", "15"],
            "--debug-level = 15",
        ),
        (
            &["--debug", "steps", "--debug-steps-scale", "0"],
            "--debug-steps-scale = 0",
        ),
        (
            &["--stereo", "checkerboard", "--eye-separation", "nan"],
            "--eye-separation = NaN",
        ),
        (
            &["--stereo", "top-bottom", "--eye-separation=-0.1"],
            "--eye-separation = -0.1",
        ),
        (
            &["--stereo", "anaglyph-dubois", "--convergence=-2"],
            "--convergence = -2",
        ),
        (
            &["--stereo", "anaglyph-dubois", "--convergence", "0"],
            "--convergence = 0",
        ),
        (
            &["--stereo", "side-by-side-full", "--width", "8193"],
            "--width = 8193",
        ),
        (&["--sao", "--sao-radius", "0"], "--sao-radius = 0"),
        (&["--sao", "--sao-bias=-1"], "--sao-bias = -1"),
        (&["--sao", "--sao-contrast", "nan"], "--sao-contrast = NaN"),
        (&["--sao", "--sao-epsilon", "0"], "--sao-epsilon = 0"),
    ];
    for (extra, want) in cases {
        let stderr = render_fails(extra);
        assert!(
            stderr.contains(want) && stderr.contains("expected"),
            "{extra:?}: {stderr}"
        );
    }
}

#[test]
fn an_unknown_stereo_mode_lists_the_modes() {
    let stderr = render_fails(&["--stereo", "anaglyph-magenta"]);
    for mode in [
        "anaglyph-true",
        "anaglyph-gray",
        "anaglyph-color",
        "anaglyph-half-color",
        "anaglyph-dubois",
        "side-by-side",
        "side-by-side-full",
        "top-bottom",
        "row-interleaved",
        "column-interleaved",
        "checkerboard",
    ] {
        assert!(stderr.contains(mode), "{mode} not listed: {stderr}");
    }
}

#[test]
fn commands_failing_after_the_device_is_up_release_everything() {
    let cases: &[(&[&str], &str)] = &[
        // The debug pass refuses the level after the grid and every other pass exist.
        (
            &["--validate", "--debug", "level", "--debug-level", "12"],
            "--debug-level",
        ),
        // A combination the renderer refuses when it is made.
        (&["--validate", "--gi", "none", "--sao"], "leave out --sao"),
        // Refused before the voxel grid is allocated, naming the flags to lower.
        (
            &["--validate", "--voxels", "16384", "--voxel-layers", "64"],
            "lower --voxels or --voxel-layers",
        ),
        // 16384² × 16 B of read-back alone exceeds what lavapipe (and most drivers)
        // allocate at once: refused before the first frame-sized allocation.
        (
            &["--validate", "--width", "16384", "--height", "16384"],
            "lower --width/--height",
        ),
    ];
    // The same grid from a scene's `[voxel]` table: the scene's keys reach the renderer (no
    // flag names a grid here) and the advice names them too.
    let scene = std::env::temp_dir().join(format!("voxgi-voxel-table-{}.toml", std::process::id()));
    std::fs::write(
        &scene,
        format!(
            "{}\n[voxel]\nresolution = 16384\nlayers = 64\n",
            include_str!("../assets/scenes/cornell.toml")
        ),
    )
    .expect("writes the scene");
    let scene = scene.to_string_lossy().into_owned();
    let from_scene: &[&str] = &["--validate", "--gi", "hemisphere", &scene];
    let want_scene =
        "lower --voxels or --voxel-layers (the scene's `[voxel] resolution` or `layers`)";
    for (extra, want) in cases.iter().copied().chain([(from_scene, want_scene)]) {
        let stderr = render_fails(extra);
        assert!(stderr.contains(want), "{extra:?}: {stderr}");
        assert!(
            !stderr.to_lowercase().contains("leak"),
            "{extra:?} leaked:\n{stderr}"
        );
        assert!(
            !stderr.contains("Validation"),
            "{extra:?} left validation messages:\n{stderr}"
        );
    }
}

/// `profile --camera-path` flies the scene's `[camera_path]`: the report says over which
/// times it measured; a scene without the table is refused before the device is up.
#[test]
fn profile_flies_the_camera_path_or_says_the_scene_has_none() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/scenes/cornell_mover.toml"
    );
    let size = ["--width", "32", "--height", "32", "--warmup", "1"];
    let mut args = vec![
        "--validate",
        "profile",
        scene,
        "--camera-path",
        "--path-frames",
        "3",
    ];
    args.extend(size);
    let out = voxgi(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // cornell_mover's path runs from 0 to 5 s through 4 keys.
    assert!(
        stdout.contains("camera path: 3 frames evenly over 0..5 s (4 keyframes)"),
        "{stdout}"
    );
    assert!(stdout.contains("(3 frames after 1 warm-up)"), "{stdout}");

    let mut args = vec!["profile", "cornell", "--camera-path"];
    args.extend(size);
    let out = voxgi(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("cornell: `voxgi profile --camera-path` needs a `[camera_path]` table"),
        "{stderr}"
    );
    // `--path-frames` means nothing without the path.
    let out = voxgi(&["profile", "cornell", "--path-frames", "3"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("--camera-path"),
        "{stderr}"
    );
}

/// `profile --stereo` lists both eyes' passes (the right eye's with `[R]`), the packing, and
/// the mono frame of the same run; where one frame cannot render the pair (`--gi ssgi` keeps
/// one history) it profiles two passes and says why; without `--stereo-path` it takes
/// multiview (lavapipe has the feature) and says why; with `--demo` it is refused.
#[test]
fn profile_stereo_lists_both_eyes_and_the_mono_frame() {
    let size = [
        "--width", "32", "--height", "32", "--frames", "3", "--warmup", "1",
    ];
    let one_frame = ["\ngbuffer ", "\ngbuffer[R] "];
    for (gi, stereo_path, path, gbuffer) in [
        ("none", Some("one-frame"), "path one-frame,", one_frame),
        (
            "ssgi",
            Some("one-frame"),
            "path two-pass (one-frame falls back: --gi ssgi",
            one_frame,
        ),
        (
            "none",
            None,
            "path multiview (default: the device has multiview",
            ["\ngbuffer_multiview ", "\ndeferred_direct[R] "],
        ),
    ] {
        let mut args = vec!["--validate", "profile", "cornell", "--gi", gi];
        args.extend(["--stereo", "anaglyph-gray"]);
        if let Some(p) = stereo_path {
            args.extend(["--stereo-path", p]);
        }
        args.extend(size);
        let out = voxgi(&args);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for want in gbuffer.into_iter().chain([
            "\ntonemap[R] ",
            "\nstereo_pack ",
            path,
            "resolution: 32x32 per eye",
            "mono frame: ",
            "stereo vs mono: ",
            "stereo vs mono, minima: ",
            "right eye's passes [R]: ",
        ]) {
            assert!(stdout.contains(want), "{gi}: no `{want}` in\n{stdout}");
        }
    }
    let out = voxgi(&["profile", "--demo", "--stereo", "anaglyph-gray"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("does not combine with --demo"),
        "{stderr}"
    );
}

#[test]
fn render_output_must_be_a_png_and_says_how_to_get_hdr() {
    // `-o x.exr` used to fail after rendering ("writing color type Rgba8 not yet supported")
    // and leave an empty file; now it is refused before the device starts, naming --exr.
    let path = std::env::temp_dir().join(format!("voxgi-cli-errors-{}.exr", std::process::id()));
    let path = path.to_string_lossy().into_owned();
    let out = voxgi(&["render", "-o", &path, "--width", "32", "--height", "32"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "-o {path} succeeded");
    assert!(
        stderr.contains(".png") && stderr.contains("--exr"),
        "the error names the format and --exr: {stderr}"
    );
    assert!(
        !std::path::Path::new(&path).exists(),
        "no file was left behind"
    );
}

/// `voxgi bench ssgi` refuses its bad inputs before the device is up, naming the flag or the
/// file and what to do.
#[test]
fn bench_ssgi_names_its_bad_inputs() {
    for (args, want) in [
        (&["--samples", "16,0"][..], "--samples = 0"),
        (&["--gi-frames", "0"], "--gi-frames = 0"),
        (&["--size", "100"], "--size must divide it"),
        (&["assets/scenes/sun.toml"], "no reference image"),
        (&["--mips", "median"], "possible values: voting, fast"),
    ] {
        let out = voxgi(&[&["bench", "ssgi"][..], args].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(want), "{args:?}: {stderr}");
    }
}

#[test]
fn view_refuses_a_save_path_it_cannot_write_before_opening_a_window() {
    // Checked before the window and the device: no display is needed to see the error.
    let dir = std::env::temp_dir();
    let missing = dir.join("voxgi-no-such-folder").join("edited.toml");
    let missing = missing.to_string_lossy().into_owned();
    let folder = dir.to_string_lossy().into_owned();
    for (path, want) in [
        (
            missing.as_str(),
            "does not exist; create it or save elsewhere",
        ),
        (folder.as_str(), "that is a folder; give a file name"),
    ] {
        let out = voxgi(&["view", "--save", path]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "--save {path} was accepted");
        assert!(
            err.contains(&format!("--save {path}")) && err.contains(want),
            "{err}"
        );
    }
}

#[test]
fn view_refuses_post_flags_out_of_range_before_opening_a_window() {
    // The viewer takes the post-processing flags `render` takes, checked against the same
    // limits (`src/limits.rs`) before the window and the device: no display is needed.
    for (args, want) in [
        (
            &["--taa", "--taa-history-weight", "1"][..],
            "--taa-history-weight = 1 is invalid",
        ),
        (&["--bloom", "2"][..], "--bloom = 2 is invalid"),
        (
            &["--auto-exposure", "--exposure-adaptation", "0"][..],
            "--exposure-adaptation = 0 is invalid",
        ),
    ] {
        let out = voxgi(&[&["view"][..], args].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "view {args:?} was accepted");
        assert!(err.contains(want), "view {args:?}: {err}");
    }
}

/// An MTL material with `Ks` but no `Ns` (what OBJ exports write for a bare metal, e.g. the
/// brass of Bitterli's staircase: `Kd 0`, `Ks 1`) renders a Phong lobe of exponent 0, which is
/// Ks/π in every direction: a white diffuse layer. Loading it says so, naming the file and the
/// material, and so does an explicit `Ns 0`; a material with an exponent loads silently.
#[test]
fn mtl_specular_without_exponent_warns_naming_the_material() {
    let dir = std::env::temp_dir().join(format!("voxgi-cli-ns-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl brass\nKd 0 0 0\nKs 1 1 1\n\
         newmtl zero\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\nNs 0\n\
         newmtl shiny\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\nNs 50\n",
    )
    .expect("writes the MTL");
    std::fs::write(
        dir.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n\
         usemtl brass\nf 1 2 3\nusemtl zero\nf 2 4 3\nusemtl shiny\nf 2 5 4\n",
    )
    .expect("writes the OBJ");
    let obj = dir.join("m.obj").to_string_lossy().into_owned();
    let out_dir = dir.join("export").to_string_lossy().into_owned();
    let out = voxgi(&["export-mitsuba", &obj, "--output", &out_dir]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "export-mitsuba failed:\n{stderr}");
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("a Phong lobe of exponent 0"))
        .collect();
    assert_eq!(warnings.len(), 2, "{stderr}");
    assert!(
        warnings[0].contains("`brass`") && warnings[0].contains("no Ns"),
        "{stderr}"
    );
    assert!(
        warnings[1].contains("`zero`") && warnings[1].contains("Ns 0"),
        "{stderr}"
    );
    assert!(!stderr.contains("`shiny`"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The negative control of the command line's teardown check on error paths: every command that
/// uses the device runs in [`voxgi::cli::with_context`], which destroys the context and checks
/// what its life left behind also when the command fails. A command body that leaks GPU memory,
/// or raises a validation message, and then fails must report both its error and the teardown's
/// finding; a body that fails cleanly reports only its error.
#[test]
fn a_failing_command_that_leaks_or_misuses_the_gpu_is_reported() {
    use voxgi::cli::{with_context, CliError, Global};
    let global = Global {
        validate: true,
        device: None,
    };
    let failure = || CliError::StereoProfile;

    let clean = with_context(&global, |_| -> Result<(), CliError> { Err(failure()) });
    assert!(
        matches!(clean, Err(CliError::StereoProfile)),
        "a clean failure: {clean:?}"
    );

    let leak = with_context(&global, |ctx| -> Result<(), CliError> {
        std::mem::forget(common::transfer_buffer(ctx, "leaked on the error path"));
        Err(failure())
    });
    match &leak {
        Err(CliError::ErrorThenTeardown { error, teardown }) => {
            assert!(matches!(**error, CliError::StereoProfile), "{leak:?}");
            // The buffer never destroyed is a validation message at device destruction, which
            // the check reports before the allocation leak it also is.
            assert!(
                matches!(
                    &**teardown,
                    CliError::Validation { count } if *count > 0
                ) || matches!(
                    &**teardown,
                    CliError::Leak { names } if names.iter().any(|n| n.contains("leaked on the error path"))
                ),
                "{leak:?}"
            );
        }
        other => panic!("a leak on an error path went unreported: {other:?}"),
    }

    let hazard = with_context(&global, |ctx| -> Result<(), CliError> {
        // The misuse tests/validation_controls.rs reports without the command line.
        let target = common::transfer_buffer(ctx, "hazard target");
        common::run_write_after_write(ctx, &target);
        Err(failure())
    });
    match &hazard {
        Err(CliError::ErrorThenTeardown { error, teardown }) => {
            assert!(matches!(**error, CliError::StereoProfile), "{hazard:?}");
            assert!(
                matches!(**teardown, CliError::Validation { count } if count > 0),
                "{hazard:?}"
            );
        }
        other => panic!("a validation message on an error path went unreported: {other:?}"),
    }
}
