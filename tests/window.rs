//! The viewer in a real window (CI: `xvfb-run -a cargo test`). Runs `voxgi --validate view` as
//! a scripted run: frames, a resize halfway (or a minimize and restore), a screenshot of the
//! last frame; the command fails on any validation message. Without a display, or without
//! openbox for the minimize test, a test fails with the hint, never passes.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The tests share one X display; the minimize test runs a window manager on it, which must
/// not manage (place, constrain) the other test's window. So they take turns.
static DISPLAY: Mutex<()> = Mutex::new(());

fn lock_display() -> std::sync::MutexGuard<'static, ()> {
    DISPLAY.lock().unwrap_or_else(|e| e.into_inner())
}

fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxgi-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create a scratch directory");
    dir
}

fn voxgi(args: &[&str]) -> std::process::Output {
    voxgi_with(args, |_| {})
}

fn voxgi_with(args: &[&str], setup: impl FnOnce(&mut Command)) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_voxgi"));
    cmd.args(args).args(fixed_size(args));
    setup(&mut cmd);
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        cmd.env("XDG_RUNTIME_DIR", scratch_dir("xdg"));
    }
    cmd.output().expect("run the voxgi binary")
}

/// The viewer's tests see the frame at the window's size: dynamic resolution (on by default,
/// 100 ms, which lavapipe misses) would change the size mid-run. Off unless the test sets it.
fn fixed_size(args: &[&str]) -> &'static [&'static str] {
    let view = args.contains(&"view");
    let sets_it = args.iter().any(|a| a.contains("frame_budget"));
    if view && !sets_it {
        &["--set", "post.frame_budget_ms=0"]
    } else {
        &[]
    }
}

fn require_display() {
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        panic!(
            "no display for the window test: run it under Xvfb, `xvfb-run -a cargo test` \
             (Debian/Ubuntu: apt-get install xvfb)"
        );
    }
}

fn assert_success(out: &std::process::Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A window manager (openbox) on the test's X display, stopped when dropped; `None` inside when
/// the display already has one.
struct WindowManager(Option<Child>);

impl Drop for WindowManager {
    fn drop(&mut self) {
        if let Some(child) = &mut self.0 {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

const WM_HINT: &str = "minimizing a window needs a window manager; under Xvfb the test starts \
                       openbox (Debian/Ubuntu: apt-get install openbox, or run tools/setup)";

fn start_window_manager(dir: &Path) -> WindowManager {
    if std::env::var_os("DISPLAY").is_none() {
        panic!(
            "the minimize test needs an X display: run it under Xvfb, `xvfb-run -a cargo test` \
             (Debian/Ubuntu: apt-get install xvfb openbox)"
        );
    }
    let ready = dir.join("wm-ready");
    let log = dir.join("wm.log");
    let mut child = Command::new("openbox")
        .arg("--sm-disable")
        .arg("--startup")
        .arg(format!("touch {}", ready.display()))
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&log).expect("create the window manager's log"))
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start openbox ({e}): {WM_HINT}"));
    let started = Instant::now();
    while !ready.exists() {
        if let Ok(Some(status)) = child.try_wait() {
            let msg = std::fs::read_to_string(&log).unwrap_or_default();
            if msg.contains("already running") {
                // The display's own window manager will do.
                return WindowManager(None);
            }
            panic!("openbox exited ({status}) before it was ready: {msg}\n{WM_HINT}");
        }
        if started.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("openbox did not start within 20 s: {WM_HINT}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    WindowManager(Some(child))
}

fn load(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
        .to_rgba8()
}

#[test]
fn viewer_renders_resizes_and_screenshots_without_validation_messages() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window");
    let shot = dir.join("shot.png");
    let out = voxgi(&[
        "--validate",
        "view",
        "--gi",
        "none",
        "--width",
        "320",
        "--height",
        "240",
        "--frames",
        "12",
        "--resize",
        "640x360",
        "--screenshot",
        shot.to_str().expect("utf-8 path"),
    ]);
    // Exit code 0 means: no validation message, screenshot written.
    assert_success(&out, "voxgi --validate view");
    let img = load(&shot);
    // The last frame was rendered after the resize reached the swapchain; the scene fills the
    // window right of the panel.
    let (w, h) = img.dimensions();
    assert_eq!(h, 360, "the screenshot is {w}x{h}");
    assert!((300..640).contains(&w), "the screenshot is {w}x{h}");
    assert_not_blank(&img);
    // With the camera untouched, the viewer shows exactly what `voxgi render` writes.
    assert_matches_render(&img, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Dynamic resolution: a budget no frame can hold drives the internal scale to its floor
/// (upscaled to the window), and the still camera then refines to the full size; validation
/// clean through both changes. With the path tracer (the default GI) each change makes a new
/// renderer (its histories have the frame's size); without GI only a new graph, and the
/// refined frame is then exactly what `voxgi render` writes.
#[test]
fn viewer_scales_down_to_hold_a_frame_budget_and_refines_when_still() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("dynres");
    for gi in ["pathtrace", "none"] {
        let shot = dir.join(format!("{gi}.png"));
        let out = voxgi_with(
            &[
                "--validate",
                "view",
                "--gi",
                gi,
                "--width",
                "400",
                "--height",
                "200",
                // 1 µs: every frame is far over it.
                "--set",
                "post.frame_budget_ms=0.001",
                "--set",
                "post.min_scale=0.25",
                "--set",
                "post.refine_frames=14",
                "--frames",
                "20",
                "--screenshot",
                shot.to_str().expect("utf-8 path"),
            ],
            |cmd| {
                cmd.env("RUST_LOG", "warn,voxgi::app=info");
            },
        );
        assert_success(
            &out,
            "voxgi --validate view --set post.frame_budget_ms=0.001",
        );
        let log = String::from_utf8_lossy(&out.stderr);
        let scales: Vec<&str> = log
            .lines()
            .filter(|l| l.contains("dynamic resolution: "))
            .collect();
        // Starts at the floor, 2/8 = 1/4 of each axis, and stays (every frame is over the
        // budget), then full size when still.
        assert_eq!(scales.len(), 2, "{gi}: {log}");
        assert!(
            scales[0].contains("(scale 2/8)") && scales[0].contains("smallest scale"),
            "{gi}: {}",
            scales[0]
        );
        assert!(
            scales[1].contains("(scale 8/8)") && scales[1].contains("refining"),
            "{gi}: {}",
            scales[1]
        );
        // The area at a quarter, upscaled (bilinear, `post.upscale`'s default); then
        // presented as it is.
        let graphs: Vec<&str> = log
            .lines()
            .filter(|l| l.contains("frame graph: "))
            .collect();
        assert!(
            graphs.iter().any(|l| l.contains(" upscaled to ")),
            "{gi}: {graphs:?}"
        );
        let last = graphs.last().expect("a graph");
        assert!(
            !last.contains(" upscaled to ") && !last.contains("upsampled"),
            "{gi}: {graphs:?}"
        );
        if gi == "pathtrace" {
            // The viewer's GI: temporal accumulation, one ray while scaled, the scene's 4
            // once refined (`post.dynamic_gi`).
            let renderers: Vec<&str> = log
                .lines()
                .filter(|l| l.contains("new renderer "))
                .collect();
            assert!(
                renderers.iter().any(|l| l.contains("1 rays")),
                "{gi}: {renderers:?}"
            );
            assert!(
                renderers.last().is_some_and(|l| l.contains("4 rays")),
                "{gi}: {renderers:?}"
            );
        }
        if gi == "pathtrace" {
            // The first (made for the scene's area once the panel's width is known), one
            // per change of scale: not one per frame.
            let renderers = log.lines().filter(|l| l.contains("new renderer ")).count();
            assert!((2..=4).contains(&renderers), "{gi}: {renderers}\n{log}");
        }
        let img = load(&shot);
        assert_eq!(img.height(), 200, "{gi}: refined to the window's height");
        if gi == "none" {
            assert_matches_render(&img, &dir);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn viewer_skips_frames_while_minimized_and_renders_after_restore() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("minimize");
    let _wm = start_window_manager(&dir);
    let shot = dir.join("shot.png");
    let out = voxgi_with(
        &[
            "--validate",
            "view",
            "--gi",
            "none",
            "--width",
            "320",
            "--height",
            "240",
            "--frames",
            "8",
            "--minimize-at",
            "3",
            "--restore-after",
            "10",
            "--screenshot",
            shot.to_str().expect("utf-8 path"),
        ],
        |cmd| {
            // X11: iconify through the window manager started above.
            cmd.env_remove("WAYLAND_DISPLAY")
                .env("RUST_LOG", "warn,voxgi::app=info");
        },
    );
    // Exit code 0 means: the window was minimized and restored (else the run fails with the
    // window manager hint), no validation message, screenshot written after the restore.
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "voxgi --validate view --minimize-at failed ({}):\n{stderr}\n{WM_HINT}",
        out.status
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let skipped: u64 = stdout
        .lines()
        .find_map(|l| {
            l.strip_prefix("skipped ")?
                .strip_suffix(" frames while minimized")?
                .parse()
                .ok()
        })
        .unwrap_or_else(|| panic!("no \"skipped N frames while minimized\" in:\n{stdout}"));
    assert!(
        skipped >= 10,
        "skipped {skipped} frames while minimized, expected at least --restore-after 10"
    );
    assert!(
        stderr.contains("restored: recreating the swapchain"),
        "the swapchain was not recreated after the restore:\n{stderr}"
    );
    let img = load(&shot);
    let (w, h) = img.dimensions();
    assert_eq!(h, 240, "the screenshot is {w}x{h}");
    assert_not_blank(&img);
    assert_matches_render(&img, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn viewer_renders_a_scene_with_gi_table_and_gi_flags_without_validation_messages() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-gi");
    // The built-in Cornell box with the path tracer and SAO chosen by the scene file, and its
    // `[post]` table; flags override the scene's bounces and exposure. The resize makes the viewer replace its renderer (the
    // path tracer's history has the frame's size).
    let cornell = include_str!("../assets/scenes/cornell.toml");
    let scene = dir.join("cornell_gi.toml");
    std::fs::write(
        &scene,
        format!(
            "{cornell}\n[gi]\nmethod = \"pathtrace\"\nrays = 2\nbounces = 3\nsao = true\n\
             sao_radius_m = 0.6\n[post]\nfxaa = true\ntonemap = \"drago\"\nexposure = 2.0\n"
        ),
    )
    .expect("write the scene");
    let shot = dir.join("shot.png");
    let out = voxgi_with(
        &[
            "--validate",
            "view",
            scene.to_str().expect("utf-8 path"),
            "--gi-bounces",
            "1",
            "--exposure",
            "3",
            "--width",
            "320",
            "--height",
            "240",
            "--frames",
            "8",
            "--resize",
            "400x300",
            "--screenshot",
            shot.to_str().expect("utf-8 path"),
        ],
        |cmd| {
            cmd.env("RUST_LOG", "warn,voxgi::app=info");
        },
    );
    assert_success(&out, "voxgi --validate view (scene with [gi])");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("indirect light: pathtrace, 2 rays, 1 bounces"),
        "the viewer did not start with the scene's path tracer and the flag's bounces:\n{stderr}"
    );
    // The scene's SAO keys and `[post]` table, the latter's exposure overridden by the flag.
    assert!(
        stderr.contains("SAO r 0.6 m")
            && stderr.contains("post-processing: fxaa, tonemap Drago × 3"),
        "the viewer did not start with the scene's SAO and [post] table:\n{stderr}"
    );
    assert!(
        stderr.contains("new renderer") && stderr.contains("x300, indirect light: pathtrace"),
        "the viewer did not make a new renderer for the resized path tracer:\n{stderr}"
    );
    let img = load(&shot);
    let (w, h) = img.dimensions();
    assert_eq!(h, 300, "the screenshot is {w}x{h}");
    assert_not_blank(&img);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `voxgi view --stereo MODE` presents the packed pair, each eye fitted so that the packing
/// fills the scene area pixel for pixel: the screenshot equals `voxgi render --stereo MODE`
/// of the same eye size and parallax (±1 step of 8 bits, as for the mono view). An anaglyph on
/// the one-frame path (one renderer of both eyes) and side-by-side-full on the two-pass path
/// (a renderer per eye in the viewer's graph; `render` reuses one renderer per eye); then the
/// fallback to two passes where one frame cannot run, with its reason.
#[test]
fn viewer_presents_stereo_packings_as_render_writes_them() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-stereo");
    for (mode, path, full) in [
        ("anaglyph-dubois", "one-frame", false),
        ("side-by-side-full", "two-pass", true),
    ] {
        let shot = dir.join(format!("{mode}.png"));
        let parallax = ["--eye-separation", "0.1", "--convergence", "1.0"];
        let mut args = vec!["--validate", "view", "--gi", "none", "--width", "400"];
        args.extend(["--height", "128", "--frames", "5", "--stereo", mode]);
        args.extend(["--stereo-path", path, "--screenshot"]);
        args.push(shot.to_str().expect("utf-8 path"));
        args.extend(parallax);
        let out = voxgi_with(&args, |cmd| {
            cmd.env("RUST_LOG", "warn,voxgi::app=info");
        });
        assert_success(&out, &format!("voxgi --validate view --stereo {mode}"));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(&format!("stereo: {path}")),
            "the viewer did not say it renders {path}:\n{stderr}"
        );
        let img = load(&shot);
        let (w, h) = img.dimensions();
        assert_eq!(h, 128, "{mode}: the screenshot is {w}x{h}");
        assert!((64..400).contains(&w), "{mode}: the screenshot is {w}x{h}");
        assert_not_blank(&img);
        let eye_w = if full { w / 2 } else { w };
        let reference = dir.join(format!("{mode}-render.png"));
        let mut args = vec!["--validate", "render", "--gi", "none", "--stereo", mode];
        let eye_w = eye_w.to_string();
        args.extend(["--width", &eye_w, "--height", "128", "-o"]);
        args.push(reference.to_str().expect("utf-8 path"));
        args.extend(parallax);
        let out = voxgi(&args);
        assert_success(&out, &format!("voxgi --validate render --stereo {mode}"));
        let reference = load(&reference);
        assert_eq!(reference.dimensions(), (w, h), "{mode}");
        let max_diff = img
            .pixels()
            .zip(reference.pixels())
            .flat_map(|(a, b)| (0..3).map(move |c| a.0[c].abs_diff(b.0[c])))
            .max()
            .unwrap_or(0);
        assert!(
            max_diff <= 1,
            "{mode}: the viewer's packing differs from `voxgi render --stereo` by up to \
             {max_diff}/255"
        );
    }
    // Where one frame cannot render the pair (screen-space GI keeps one history), the viewer
    // renders two passes and says why, as `voxgi render --stereo` does.
    let shot = dir.join("fallback.png");
    let mut args = vec!["--validate", "view", "--gi", "ssgi", "--width", "400"];
    args.extend([
        "--height",
        "128",
        "--frames",
        "4",
        "--stereo",
        "row-interleaved",
    ]);
    args.extend(["--screenshot", shot.to_str().expect("utf-8 path")]);
    let out = voxgi_with(&args, |cmd| {
        cmd.env("RUST_LOG", "warn,voxgi::app=info");
    });
    assert_success(
        &out,
        "voxgi --validate view --gi ssgi --stereo row-interleaved",
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        // The path that falls back is the device's default (multiview or one-frame).
        stderr.contains("stereo: two-pass (") && stderr.contains("falls back: --gi ssgi"),
        "the viewer did not say why it renders two passes:\n{stderr}"
    );
    assert_not_blank(&load(&shot));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `voxgi view --taa` on a scene with a moving object (its G-buffer draws motion vectors):
/// TAA upsampling against the bilinear blit (`post.upscale`), the camera still at a quarter
/// of the scene's area per axis (a budget no frame holds, no refining): after 24 frames (the
/// 16 jitters and more) the TAA-upsampled screenshot, at the area's size, is closer to the
/// full-size `voxgi render` of the same view than the internal frame upscaled bilinearly
/// (what the bilinear blit shows; the image crate's triangle filter is the same tent filter
/// over the same texel centres), by relMSE of the 8-bit values. Direct light only, so the
/// difference is the upsampling's and not the GI's noise. Validation clean.
#[test]
fn viewer_taa_upsampling_regains_detail_the_bilinear_blit_loses() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("taau");
    let shot = |upscale: &str| {
        let path = dir.join(format!("{upscale}.png"));
        let out = voxgi_with(
            &[
                "--validate",
                "view",
                "--gi",
                "none",
                "--width",
                "720",
                "--height",
                "360",
                "--set",
                "post.frame_budget_ms=0.001",
                "--set",
                "post.min_scale=0.25",
                "--set",
                "post.refine_frames=0",
                "--set",
                &format!("post.upscale={upscale}"),
                "--frames",
                "24",
                "--screenshot",
                path.to_str().expect("utf-8 path"),
            ],
            |cmd| {
                cmd.env("RUST_LOG", "warn,voxgi::app=info");
            },
        );
        assert_success(&out, &format!("voxgi --validate view (upscale {upscale})"));
        load(&path)
    };
    let taa = shot("taa");
    let small = shot("bilinear");
    let (w, h) = taa.dimensions();
    assert!(
        small.width() * 3 < w && small.height() * 3 < h,
        "the bilinear run's frame {:?} is not a quarter of the area {:?}",
        small.dimensions(),
        (w, h)
    );
    let bilinear = image::imageops::resize(&small, w, h, image::imageops::FilterType::Triangle);
    // The viewer's built-in scene and camera, as `assert_matches_render` renders them.
    let full = render_like_viewer(w, h, &dir);
    // relMSE of 8-bit values (Rousselle et al. 2011's ε = 0.01 on values in [0, 1]).
    let rel_mse = |a: &image::RgbaImage| {
        let sum: f64 = a
            .pixels()
            .zip(full.pixels())
            .flat_map(|(p, q)| (0..3).map(move |c| (p.0[c], q.0[c])))
            .map(|(x, r)| {
                let (x, r) = (f64::from(x) / 255.0, f64::from(r) / 255.0);
                (x - r).powi(2) / (r * r + 0.01)
            })
            .sum();
        sum / f64::from(w * h * 3)
    };
    let (e_taa, e_bilinear) = (rel_mse(&taa), rel_mse(&bilinear));
    eprintln!(
        "{w}x{h} from {:?} after 24 still frames: relMSE TAA upsampling {e_taa:.5}, bilinear \
         {e_bilinear:.5}",
        small.dimensions()
    );
    assert!(
        e_taa < e_bilinear,
        "TAA upsampling ({e_taa}) is not closer to the full-size render than bilinear \
         ({e_bilinear})"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// every frame is one jittered TAA frame blended into the history, so the scripted run's last
/// frame, the K-th of its renderer (the viewer logs K), is what a headless
/// `voxgi render --taa --taa-frames K` of the same size computes (the same Halton jitters, the
/// same blend weights 1/(n+1) in the same order): within ±1 step of 8 bits, the bound of the
/// mono view. A negative control: the render without TAA (one unjittered frame) differs at
/// the edges by more than that.
#[test]
fn viewer_accumulates_taa_per_frame_as_render_does() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-taa");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cornell_mover.toml");
    let shot = dir.join("taa.png");
    let out = voxgi_with(
        &[
            "--validate",
            "view",
            scene.to_str().expect("utf-8 path"),
            "--gi",
            "none",
            "--taa",
            "--width",
            "480",
            "--height",
            "160",
            "--frames",
            "8",
            "--screenshot",
            shot.to_str().expect("utf-8 path"),
        ],
        |cmd| {
            cmd.env("RUST_LOG", "warn,voxgi::app=info");
        },
    );
    assert_success(&out, "voxgi --validate view --taa");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("post-processing: taa α 0.9"),
        "the viewer did not start with TAA:\n{stderr}"
    );
    let frames: u32 = stderr
        .lines()
        .filter_map(|l| l.split_once("the last frame is frame ").map(|(_, r)| r))
        .filter_map(|r| r.split_whitespace().next()?.parse().ok())
        .next_back()
        .unwrap_or_else(|| panic!("the viewer did not log its renderer's frames:\n{stderr}"));
    assert_taa_screenshot_is_the_render(&dir, &scene, &shot, frames);
    let _ = std::fs::remove_dir_all(&dir);
}

/// TAA switched on at runtime with a real click (xdotool) on the panel's checkbox, scrolled
/// into view with the wheel in a 320 px window: the viewer makes a renderer with TAA and
/// blends one jittered frame per viewer frame, so F12's screenshot, the K-th frame of that
/// renderer (the viewer logs K), is what `voxgi render --taa --taa-frames K` computes (±1 step
/// of 8 bits, as above), and not the render without TAA. Validation clean.
#[test]
fn viewer_turns_taa_on_with_a_click_and_blends_a_frame_per_frame() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-taa-click");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cornell_mover.toml");
    let shot = dir.join("taa.png");
    let shot_arg = shot.to_str().expect("utf-8 path");
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        scene.to_str().expect("utf-8 path"),
        "--gi",
        "none",
        "--width",
        "480",
        "--height",
        "320",
        "--screenshot",
        shot_arg,
    ]);
    let first = s.wait_for("panel: scrolled");
    s.settled(first, "panel: scrolled", 5);
    let taa = scroll_panel_to(&mut s, "post TAA", 320.0);
    s.click(taa);
    let made = s.wait_for("new renderer");
    assert!(
        made.contains("post-processing: taa α 0.9"),
        "the click made no renderer with TAA: {made}"
    );
    // Off the checkbox (its tooltip), onto the panel's heading; TAA blends a few frames.
    s.hover([60.0, 10.0]);
    s.frames(2);
    s.key("F12");
    s.wait_for(&format!("wrote {shot_arg}"));
    let line = s.wait_for("screenshot: frame ");
    let frames: u32 = line
        .split_once("screenshot: frame ")
        .and_then(|(_, r)| r.split_whitespace().next()?.parse().ok())
        .unwrap_or_else(|| panic!("no frame count in {line}"));
    s.finish();
    assert_taa_screenshot_is_the_render(&dir, &scene, &shot, frames);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn viewer_shows_voxel_debug_views_without_validation_messages() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-debug");
    // The albedo view also creates and writes the albedo volume; the atlas view draws an
    // atlas instead of casting rays.
    for view in ["voxels", "albedo", "atlas"] {
        viewer_shows_debug_view(&dir, view);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn viewer_panel_table_keeps_names_and_times_apart() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-panel");
    // The default window, and one narrower than the panel's default width (240 points), which
    // squeezes the panel: long pass names must give way, not run into their times.
    let mut faults = Vec::new();
    for (width, height, resize) in [(1280, 720, None), (640, 480, Some((160, 400)))] {
        let shot = dir.join("shot.png");
        let (w, h) = (width.to_string(), height.to_string());
        let mut args = vec![
            "--validate",
            "view",
            "--gi",
            "none",
            "--width",
            &w,
            "--height",
            &h,
        ];
        let resize_arg = resize.map(|(w, h): (u32, u32)| format!("{w}x{h}"));
        if let Some(r) = &resize_arg {
            args.extend(["--resize", r.as_str()]);
        }
        // Enough frames after the resize for timestamps to come back (the graph is rebuilt
        // and the timings restart); the table then has every pass of the frame.
        args.extend([
            "--frames",
            "10",
            "--screenshot",
            shot.to_str().expect("utf-8 path"),
        ]);
        let out = voxgi_with(&args, |cmd| {
            cmd.env("RUST_LOG", "warn,voxgi::app=info");
        });
        assert_success(&out, "voxgi --validate view (panel table)");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let (window_width, window_height) = resize.unwrap_or((width, height));
        faults.extend(panel_table_faults(
            &stderr,
            window_width as f32,
            window_height as f32,
        ));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        faults.is_empty(),
        "the panel's GPU-time table:\n{}",
        faults.join("\n")
    );
}

/// A window 320 px high is shorter than the panel's contents: at first the last section's
/// "Screenshot" button lies below the window; the mouse wheel over the panel (real X button 5
/// events through xdotool) scrolls the contents to their bottom, and a click on the button,
/// now in view, writes the screenshot. Validation clean, teardown included.
#[test]
fn viewer_panel_scrolls_to_its_last_section_with_the_wheel() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-scroll");
    let shot = dir.join("shot.png");
    let shot_arg = shot.to_str().expect("utf-8 path");
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        "--gi",
        "none",
        "--width",
        "400",
        "--height",
        "320",
        "--screenshot",
        shot_arg,
    ]);
    // The GPU-time table fills in over the first frames: until the layout settles.
    let first = s.wait_for("panel: scrolled");
    let top = panel_scroll(&s.settled(first, "panel: scrolled", 5));
    assert_eq!(top.offset, 0.0, "{top:?}");
    assert!(
        top.view <= 320.0 && top.content > top.view && top.max > 0.0,
        "nothing to scroll in a 320 px window: {top:?}"
    );
    assert!(
        top.button[1] > 320.0,
        "the Screenshot button is in view without scrolling: {top:?}"
    );
    let bottom = scroll_panel_to_bottom(&mut s, &top);
    assert!(
        bottom.offset == bottom.max && bottom.offset > 0.0,
        "the wheel did not scroll to the bottom: {bottom:?}"
    );
    assert!(
        (0.0..320.0).contains(&bottom.button[1]),
        "the Screenshot button is not in the window after scrolling: {bottom:?}"
    );
    // A click egui does not take (the panel still laying out or scrolling) is tried again
    // at where the button is then, a few times: the test is about reaching the button.
    let wrote = format!("wrote {shot_arg}");
    let mut button = bottom.button;
    for attempt in 1.. {
        s.click(button);
        if s.within_frames(&wrote, 10).is_some() {
            break;
        }
        assert!(
            attempt < 4,
            "{attempt} clicks on the Screenshot button missed:\n{}",
            s.log
        );
        let line = s.log.lines().rev().find(|l| l.contains("panel: scrolled"));
        button = panel_scroll(line.expect("a scroll line")).button;
        eprintln!("click {attempt} missed the Screenshot button; again at {button:?}");
    }
    s.finish();
    assert_not_blank(&load(&shot));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Turns the mouse wheel over the panel (X button 5) until its contents, scrolled as `from`
/// says, reach their bottom; returns the scroll state there.
fn scroll_panel_to_bottom(s: &mut EditSession, from: &PanelScroll) -> PanelScroll {
    const LOG: &str = "panel: scrolled";
    // Each notch scrolls at least 50 points (egui's line height for wheels; 100 under Xvfb):
    // enough notches to pass the bottom, where the area stops.
    let notches = ((from.max - from.offset) / 50.0).ceil() as u32 + 4;
    s.hover([100.0, 160.0]);
    xdotool(&[
        "click",
        "--repeat",
        &notches.to_string(),
        "--delay",
        "50",
        "5",
    ]);
    loop {
        let line = s.wait_for(LOG);
        let now = panel_scroll(&line);
        if now.offset == now.max {
            break panel_scroll(&s.settled(line, LOG, 2));
        }
    }
}

/// Turns the wheel over the panel a notch at a time (X button 5 down, 4 up; 100 points a
/// notch under Xvfb) until its control `name` lies within the window's rows
/// [20, `height` − 20), wider than a notch; returns where it is then.
fn scroll_panel_to(s: &mut EditSession, name: &str, height: f32) -> [f32; 2] {
    s.hover([100.0, 160.0]);
    for _ in 0..30 {
        let at = panel_spot(s, name, false);
        if (20.0..height - 20.0).contains(&at[1]) {
            return at;
        }
        xdotool(&["click", if at[1] >= height - 20.0 { "5" } else { "4" }]);
    }
    panic!("the panel did not scroll `{name}` into view:\n{}", s.log)
}

/// Where the panel's control `name` is (window px) once it stays put for two frames: where the
/// viewer logged it last (it logs a control when it appears or moves), or with `fresh` where
/// it logs it next (a combo's entries, logged anew each time the combo opens).
fn panel_spot(s: &mut EditSession, name: &str, fresh: bool) -> [f32; 2] {
    let want = format!("panel: `{name}` at");
    let first = if fresh {
        s.wait_for(&want)
    } else {
        // Reads what arrived into the session's log, then looks there.
        s.drain("");
        match s.log.lines().rev().find(|l| l.contains(&want)) {
            Some(line) => line.to_owned(),
            None => s.wait_for(&want),
        }
    };
    logged_point(&s.settled(first, &want, 2), "at")
}

/// The panel's stereo packing turned on, changed and off with real clicks (xdotool): in a
/// window 320 px high the wheel scrolls the panel down to the "Stereo" section; a click opens
/// it, a click opens the packing combo and one picks anaglyph-dubois: F12's screenshot equals
/// `voxgi render --stereo anaglyph-dubois` of the same size and parallax (±1 step of 8 bits,
/// as the viewer's startup packing does). Then side-by-side-full (each eye half the area's
/// width), likewise; then "off": the screenshot is the mono `voxgi render` again. Validation
/// clean, teardown included.
#[test]
fn viewer_switches_stereo_on_and_off_from_the_panel() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("window-stereo-switch");
    let shot = dir.join("shot.png");
    let shot_arg = shot.to_str().expect("utf-8 path");
    let parallax = ["--eye-separation", "0.1", "--convergence", "1.0"];
    let mut args = vec!["--validate", "view", "--gi", "none", "--width", "400"];
    args.extend(["--height", "320", "--screenshot", shot_arg]);
    args.extend(parallax);
    let mut s = EditSession::start(&args);
    let first = s.wait_for("panel: scrolled");
    let top = panel_scroll(&s.settled(first, "panel: scrolled", 5));
    scroll_panel_to_bottom(&mut s, &top);
    let in_window = |p: [f32; 2], what: &str| {
        assert!(
            (0.0..400.0).contains(&p[0]) && (0.0..320.0).contains(&p[1]),
            "{what} at {p:?} is not in the 400x320 window"
        );
        p
    };
    let header = panel_spot(&mut s, "stereo section", false);
    s.click(in_window(header, "the Stereo header"));
    let pick = |s: &mut EditSession, entry: &str| {
        let combo = panel_spot(s, "stereo packing", false);
        s.click(in_window(combo, "the packing combo"));
        let name = format!("stereo packing: {entry}");
        let entry = panel_spot(s, &name, true);
        s.click(in_window(entry, &name));
    };
    // On (a new renderer of both eyes), another packing (each eye half as wide: a new graph),
    // off (a new mono renderer); each screenshot once the viewer's graph presents it.
    let mut shots = Vec::new();
    for (entry, presents) in [
        ("anaglyph-dubois", "anaglyph-dubois"),
        ("side-by-side-full", "side-by-side-full"),
        ("off", "mono"),
    ] {
        pick(&mut s, entry);
        let line = s.wait_for(&format!("frame graph: {presents}"));
        // The panel may resize the area once more: read what arrived meanwhile.
        s.settled(line, "frame graph: ", 2);
        s.key("F12");
        s.wait_for(&format!("wrote {shot_arg}"));
        shots.push((entry, load(&shot)));
    }
    s.finish();
    let mono = shots
        .pop()
        .map(|(_, img)| img)
        .expect("the mono screenshot");
    for (mode, img) in &shots {
        let (w, h) = img.dimensions();
        assert_not_blank(img);
        // Each eye fills the scene area (the mono image), or half its width (rounded down)
        // side by side.
        let full = *mode == "side-by-side-full";
        let eye_w = if full { mono.width() / 2 } else { mono.width() };
        let packed_w = if full { 2 * eye_w } else { eye_w };
        assert_eq!(
            (w, h),
            (packed_w, mono.height()),
            "{mode}: the packing against the mono {:?}",
            mono.dimensions()
        );
        let reference = dir.join(format!("{mode}-render.png"));
        let (ws, hs) = (eye_w.to_string(), h.to_string());
        let mut args = vec!["--validate", "render", "--gi", "none", "--stereo", mode];
        args.extend(["--width", &ws, "--height", &hs, "-o"]);
        args.push(reference.to_str().expect("utf-8 path"));
        args.extend(parallax);
        let out = voxgi(&args);
        assert_success(&out, &format!("voxgi --validate render --stereo {mode}"));
        let diff = max_channel_diff(img, &load(&reference));
        assert!(
            diff <= 1,
            "after switching to {mode} the viewer differs from `voxgi render --stereo` by up \
             to {diff}/255"
        );
    }
    // The mono image is not the anaglyph: the checks above saw the switch, not the mono view.
    assert!(
        max_channel_diff(&shots[0].1, &mono) > 16,
        "the anaglyph equals the mono view"
    );
    assert_matches_render(&mono, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The panel's scroll state as the viewer logs it (window px).
#[derive(Debug)]
struct PanelScroll {
    offset: f32,
    max: f32,
    content: f32,
    view: f32,
    button: [f32; 2],
}

/// Parses `panel: scrolled O of M px (contents C px in a V px view); screenshot button at
/// [x, y] (window px)`.
fn panel_scroll(line: &str) -> PanelScroll {
    let rest = line
        .split_once("panel: scrolled ")
        .unwrap_or_else(|| panic!("not a scroll line: {line}"))
        .1;
    let words: Vec<&str> = rest.split_whitespace().collect();
    let num = |i: usize| -> f32 {
        words
            .get(i)
            .map(|w| w.trim_start_matches('('))
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("no number at word {i} of {line}"))
    };
    PanelScroll {
        offset: num(0),
        max: num(2),
        content: num(5),
        view: num(9),
        button: logged_point(line, "at"),
    }
}

/// A rectangle `[min x, min y, max x, max y]` of the viewer's panel log.
fn rect(v: &serde_json::Value) -> [f32; 4] {
    let a: Vec<f32> = v
        .as_array()
        .unwrap_or_else(|| panic!("not a rectangle: {v}"))
        .iter()
        .map(|x| x.as_f64().expect("a number") as f32)
        .collect();
    a.try_into()
        .unwrap_or_else(|_| panic!("not 4 numbers: {v}"))
}

/// What is wrong with the GPU-time table the viewer drew on its last frame (logged as "panel
/// timing table: JSON", positions in points): a pass name running into its time, times not
/// ending at one right edge, rows overlapping, a cell outside the panel's contents or across
/// the window, the panel's scroll area out of the window or scrolled. Panics when the table
/// is missing or lacks the frame's passes.
fn panel_table_faults(stderr: &str, window_width: f32, window_height: f32) -> Vec<String> {
    let json = stderr
        .lines()
        .filter_map(|l| l.split_once("panel timing table: ").map(|(_, j)| j))
        .next_back()
        .unwrap_or_else(|| panic!("the viewer did not log its panel table:\n{stderr}"));
    let table: serde_json::Value = serde_json::from_str(json).expect("the table is JSON");
    let panel = rect(&table["panel"]);
    let rows = table["rows"].as_array().expect("rows");
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["name"].as_str().expect("a name"))
        .collect();
    // The direct-light frame's passes (at least shadows, G-buffer, lighting, tone mapping),
    // then the total.
    assert!(
        // The cached shadow maps are drawn per layer (`shadow_depth[0]`).
        names.len() >= 5
            && names.iter().any(|n| n.starts_with("shadow_depth"))
            && names.last() == Some(&"total"),
        "the table lists {names:?}"
    );
    // The panel's scroll area: within the panel's and the window's height, and not scrolled
    // (the scripted run turns no wheel).
    let scroll = &table["scroll"];
    let view = rect(&scroll["view"]);
    let number = |key: &str| scroll[key].as_f64().expect("a number") as f32;
    let (offset, content) = (number("offset"), number("content_height"));
    let mut faults = Vec::new();
    if view[1] < panel[1].max(0.0) || view[3] > panel[3].min(window_height) {
        faults.push(format!(
            "{window_width} px: scroll view {view:?} outside the panel {panel:?} or the window"
        ));
    }
    if offset != 0.0 || content <= 0.0 {
        faults.push(format!(
            "{window_width} px: scrolled to {offset} of contents {content} points high"
        ));
    }
    // Inside the panel's contents, and in view across: a window narrower than the panel's
    // widest control cuts the panel off, not the table (under Xvfb a point is a pixel). Below
    // a short window the contents scroll: down to their height.
    let top = view[1] - offset;
    let inside = |r: [f32; 4]| {
        r[0] >= panel[0].max(0.0)
            && r[1] >= top
            && r[2] <= panel[2].min(window_width)
            && r[3] <= top + content
    };
    let right = rect(&rows[0]["time_rect"])[2];
    let mut above = f32::NEG_INFINITY;
    for (row, name) in rows.iter().zip(&names) {
        let (n, t) = (rect(&row["name_rect"]), rect(&row["time_rect"]));
        if n[2] > t[0] {
            faults.push(format!(
                "{window_width} px, {name}: name {n:?} runs into time {t:?}"
            ));
        }
        // A hundredth of a point is far below a pixel: right-aligned labels end at one x.
        if (t[2] - right).abs() > 0.01 {
            faults.push(format!(
                "{window_width} px, {name}: time ends at x = {}, not {right}",
                t[2]
            ));
        }
        if n[1].min(t[1]) < above {
            faults.push(format!(
                "{window_width} px, {name}: row overlaps the row above"
            ));
        }
        above = n[3].max(t[3]);
        for (what, r) in [("name", n), ("time", t)] {
            if !inside(r) {
                faults.push(format!(
                    "{window_width} px, {name}: {what} {r:?} outside the panel {panel:?} or the window"
                ));
            }
        }
    }
    // The frame-time graph below the table: in the panel's contents, below the table,
    // over the frames whose timings came back, each series a family of the table's passes
    // (the name before `[`) or "other".
    let graph = &table["graph"];
    let g = rect(&graph["rect"]);
    if !inside(g) || g[1] < above {
        faults.push(format!(
            "{window_width} px: graph {g:?} outside the panel {panel:?} or over the table"
        ));
    }
    let frames = graph["frames"].as_u64().expect("frames");
    let series = graph["series"].as_array().expect("series");
    if frames == 0 || series.is_empty() {
        faults.push(format!("{window_width} px: empty graph {graph}"));
    }
    for s in series {
        let name = s["name"].as_str().expect("a name");
        let ms = s["mean_ms"].as_f64().expect("a mean");
        let family = names.iter().any(|n| n.split('[').next() == Some(name));
        if !(family || name == "other") || !(ms.is_finite() && ms >= 0.0) {
            faults.push(format!(
                "{window_width} px: series {name} ({ms} ms) of {names:?}"
            ));
        }
    }
    faults
}

fn viewer_shows_debug_view(dir: &Path, view: &str) {
    let shot = dir.join(format!("{view}.png"));
    let out = voxgi_with(
        &[
            "--validate",
            "view",
            "--gi",
            "none",
            "--debug",
            view,
            "--width",
            "320",
            "--height",
            "240",
            "--frames",
            "6",
            "--screenshot",
            shot.to_str().expect("utf-8 path"),
        ],
        |_| {},
    );
    assert_success(&out, &format!("voxgi --validate view --debug {view}"));
    assert_not_blank(&load(&shot));
}

fn assert_not_blank(img: &image::RgbaImage) {
    let mut sum = 0.0f64;
    let mut colors = std::collections::HashSet::new();
    for p in img.pixels() {
        let [r, g, b, _] = p.0;
        sum += (0.2126 * f64::from(r) + 0.7152 * f64::from(g) + 0.0722 * f64::from(b)) / 255.0;
        colors.insert([r, g, b]);
    }
    let mean = sum / f64::from(img.width() * img.height());
    assert!(
        mean > 0.05,
        "the screenshot is nearly black (mean luma {mean:.4})"
    );
    assert!(
        colors.len() > 2,
        "the screenshot has {} colors",
        colors.len()
    );
}

/// With the camera untouched, the viewer shows exactly what `voxgi render` writes.
fn assert_matches_render(img: &image::RgbaImage, dir: &Path) {
    let (w, h) = img.dimensions();
    let reference = render_like_viewer(w, h, dir);
    let max_diff = img
        .pixels()
        .zip(reference.pixels())
        .flat_map(|(a, b)| (0..3).map(move |c| a.0[c].abs_diff(b.0[c])))
        .max()
        .unwrap_or(0);
    assert!(
        max_diff <= 1,
        "the viewer's frame differs from `voxgi render` by up to {max_diff}/255"
    );
}

/// `voxgi --validate render --gi none` of the viewer's built-in scene and camera at `w`×`h`,
/// written into `dir` and read back.
fn render_like_viewer(w: u32, h: u32, dir: &Path) -> image::RgbaImage {
    let png = dir.join("render.png");
    let out = voxgi(&[
        "--validate",
        "render",
        "--gi",
        "none",
        "--width",
        &w.to_string(),
        "--height",
        &h.to_string(),
        "-o",
        png.to_str().expect("utf-8 path"),
    ]);
    assert_success(&out, "voxgi --validate render");
    load(&png)
}

/// Runs `xdotool ARGS` on the test's display; without xdotool the test fails with the hint.
/// Every call has a time limit: `search --sync` waits forever for a window that never comes
/// (a viewer that failed to start).
fn xdotool(args: &[&str]) -> String {
    const LIMIT: Duration = Duration::from_secs(60);
    let mut child = Command::new("xdotool")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| {
            panic!(
                "cannot run xdotool ({e}): the input test drives the window with real X events \
                 (Debian/Ubuntu: apt-get install xdotool, or run tools/setup)"
            )
        });
    let started = Instant::now();
    while child.try_wait().expect("poll xdotool").is_none() {
        if started.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("xdotool {args:?} did not finish within {LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("collect xdotool's output");
    assert!(
        out.status.success(),
        "xdotool {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// Parses `key = [x, y, z]` from the viewer's "camera at exit" table.
fn camera_vec(stdout: &str, key: &str) -> glam::Vec3 {
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix(key)?.trim_start().strip_prefix('='))
        .unwrap_or_else(|| panic!("no `{key} = [..]` in the viewer's output:\n{stdout}"));
    let v: Vec<f32> = line
        .trim()
        .trim_start_matches('[')
        .trim_end_matches(']')
        .split(',')
        .map(|x| x.trim().parse().expect("a number"))
        .collect();
    glam::Vec3::from_slice(&v)
}

#[test]
fn viewer_flies_with_real_keyboard_and_mouse_events() {
    require_display();
    let _display = lock_display();
    // The viewer runs until Escape; X events go through the server (XTEST), the same path as a
    // person's keyboard and mouse, so winit's event decoding is part of what is tested.
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        "--gi",
        "none",
        "--width",
        "480",
        "--height",
        "320",
    ]);
    // Hold W: fly forward (the fly camera integrates frame times) until 10 cm further in.
    let first = s.frames(1);
    s.hold_until("w", "the camera 10 cm forward", |f| {
        f.position.z - first.position.z > 0.1
    });
    // Look right: drag with the right button held, over the scene (right of the panel), a
    // frame per step.
    s.hover([400.0, 160.0]);
    xdotool(&["mousedown", "3"]);
    s.frames(1);
    for _ in 0..5 {
        xdotool(&["mousemove_relative", "--", "10", "0"]);
        s.frames(1);
    }
    xdotool(&["mouseup", "3"]);
    s.frames(1);
    let (_, stdout) = s.finish_with_stdout();

    // The built-in Cornell box's camera: at z = -0.8 looking along +Z.
    let start = glam::Vec3::new(0.278, 0.273, -0.8);
    let position = camera_vec(&stdout, "position");
    let forward = camera_vec(&stdout, "forward");
    let moved = position - start;
    assert!(
        moved.z > 0.05 && moved.x.abs() < 0.2 * moved.z && moved.y.abs() < 1e-4,
        "holding W should fly forward along +Z; moved by {moved}"
    );
    // Dragging right turns right: from +Z towards -X (screen right of a camera looking along
    // +Z with y up is -X).
    assert!(
        forward.x < -0.05 && forward.y.abs() < 1e-3,
        "dragging right should turn right; forward is {forward}"
    );
}

/// The `O` key switches the camera to orthographic projection (the camera printed at exit says
/// so), and under `--gi ssgi`, which cannot render it, the switch is refused with the reason
/// and the camera stays perspective. X events through xdotool, as above.
#[test]
fn viewer_switches_to_orthographic_with_o_unless_the_gi_cannot() {
    require_display();
    let _display = lock_display();
    for gi in ["none", "ssgi"] {
        let mut s = EditSession::start(&[
            "--validate",
            "view",
            "--gi",
            gi,
            "--width",
            "480",
            "--height",
            "320",
        ]);
        // The switch is applied (or refused) in the frame after the press. A press can be
        // lost while the window is still being mapped and focused (under load): without the
        // switch or its refusal in the log 10 frames later, O is pressed again, a few times.
        // (O toggles, but a press that arrived shows in the log well before 10 frames, so a
        // second press never undoes a first.)
        let switched =
            |l: &str| l.contains("projection: ") || l.contains("projection not switched");
        for attempt in 1.. {
            s.key("o");
            if s.within_frames_where(10, switched).is_some() {
                break;
            }
            assert!(
                attempt < 5,
                "{gi}: {attempt} presses of O, and neither the switch nor its refusal in the \
                 log:\n{}",
                s.log
            );
            eprintln!("{gi}: press {attempt} of O not seen in 10 frames; again");
        }
        let (stderr, stdout) = s.finish_with_stdout();
        let ortho = stdout.contains("projection = \"orthographic\"");
        match gi {
            "none" => assert!(ortho, "O did not switch to orthographic:\n{stdout}"),
            _ => {
                assert!(!ortho, "--gi ssgi switched to orthographic:\n{stdout}");
                assert!(
                    stderr.contains("projection not switched: --gi ssgi cannot render"),
                    "no reason for the refused switch:\n{stderr}"
                );
            }
        }
    }
}

/// Waits up to 60 s for `child` to exit after Escape, killing it past that.
fn wait_for_exit(child: &mut Child, what: &str) {
    let started = Instant::now();
    while child.try_wait().expect("poll the viewer").is_none() {
        if started.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: the viewer did not close within 60 s of Escape");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A storm of window events a person could cause in seconds: resizes (down to 1×1 and 2×2,
/// narrower than the panel), a minimize and restore, and GI switches with the `G` key (every
/// method, each a new renderer), interleaved. The run must survive with no validation message
/// (`--validate` fails the exit status on any, teardown included) and exit cleanly on Escape.
/// Every external wait has a time limit (`xdotool` calls 60 s, the exit 60 s).
#[test]
fn viewer_survives_a_storm_of_resizes_minimizes_and_gi_switches() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("storm");
    let _wm = start_window_manager(&dir);
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        "--gi",
        "none",
        "--width",
        "320",
        "--height",
        "240",
    ]);
    let window = s.window.clone();
    let focus = || xdotool(&["windowactivate", "--sync", &window]);
    focus();
    // (width, height) of each resize, then whether to press G after it.
    let steps: [(&str, &str, bool); 8] = [
        ("200", "150", true),
        ("1", "1", false),
        ("64", "48", true),
        ("2", "2", true),
        ("500", "300", false),
        ("40", "400", true),
        ("300", "30", true),
        ("320", "240", false),
    ];
    let mut methods = ["hemisphere", "pathtrace", "vpl", "ssgi", "none"].into_iter();
    for (i, (w, h, switch)) in steps.into_iter().enumerate() {
        // No --sync: the window manager may refuse a tiny size, and the viewer must cope
        // with whatever size it gets. A frame or two at whatever size that is.
        xdotool(&["windowsize", &window, w, h]);
        s.frames(2);
        if i == 3 {
            xdotool(&["windowminimize", "--sync", &window]);
            s.wait_for("minimized: window");
            focus();
            s.wait_for("restored: recreating the swapchain");
        }
        if switch {
            // Real key events go to the focused window (XTEST, as a keyboard's would).
            focus();
            xdotool(&["key", "g"]);
            // Each press is a new renderer with the next method (none → hemisphere → … →
            // ssgi → none): wait for it, at whatever size the window has now.
            let method = methods.next().expect("five presses");
            s.wait_for(&format!("indirect light: {method}"));
        }
    }
    focus();
    let log = s.finish();
    assert!(!log.contains("Validation"), "{log}");
    assert_eq!(methods.next(), None, "every method was switched to");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `voxgi view --budget-ms` starts with `voxgi tune`'s choice from the sweep (the panel's "best
/// within budget" button applies the same `bench::sweep::tune_from_dir`). On the committed
/// lavapipe sweep of the Cornell box the most accurate row within 100 ms is the path tracer
/// with 4 rays and 1 frame (75 ms, relMSE 0.045; docs/sweep/sweep.csv).
#[test]
fn viewer_starts_with_the_best_configuration_within_a_budget() {
    require_display();
    let _display = lock_display();
    let sweep = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/sweep");
    let out = voxgi_with(
        &[
            "--validate",
            "view",
            "cornell",
            "--sweep",
            sweep.to_str().expect("utf-8 path"),
            "--budget-ms",
            "100",
            "--width",
            "320",
            "--height",
            "240",
            "--frames",
            "3",
        ],
        |cmd| {
            cmd.env("RUST_LOG", "warn,voxgi::app=info");
        },
    );
    assert_success(&out, "voxgi --validate view --budget-ms 100");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stdout.contains("best within 100 ms: pathtrace gi-rays=4 gi-frames=1"),
        "{stdout}"
    );
    assert!(
        stderr.contains("indirect light: pathtrace, 4 rays"),
        "the viewer did not start with the tuned path tracer:\n{stderr}"
    );
    // No sweep there: a clear error naming the file, before any window.
    let missing = voxgi(&[
        "view",
        "cornell",
        "--sweep",
        "/nonexistent",
        "--budget-ms",
        "100",
    ]);
    assert!(!missing.status.success());
    let err = String::from_utf8_lossy(&missing.stderr);
    assert!(err.contains("/nonexistent/sweep.csv"), "{err}");
}

/// A viewer driven by real X events (XTEST through `xdotool`) whose log the test reads line by
/// line: the editor logs what it selected, where the selection's handles are and what it
/// saved, and every presented frame (at debug level: its number, size and camera), so the test
/// can aim its clicks and wait for each step instead of sleeping. Every wait has a time limit
/// (90 s: a new renderer on lavapipe under load) and fails with the log.
struct EditSession {
    child: Child,
    window: String,
    lines: std::sync::mpsc::Receiver<String>,
    reader: Option<std::thread::JoinHandle<()>>,
    /// The log read so far, without the per-frame lines.
    log: String,
    /// The last presented frame the log reported.
    frame: Option<Frame>,
}

/// A presented frame as the viewer logs it (`frame N presented at WxH (K of its renderer);
/// camera at [x, y, z] looking [x, y, z]`), as far as the tests read it.
#[derive(Clone, Copy, Debug)]
struct Frame {
    number: u64,
    size: (u32, u32),
    /// Where the camera is (local coordinates).
    position: glam::Vec3,
}

impl Frame {
    fn parse(line: &str) -> Option<Frame> {
        let rest = line.split_once("frame ")?.1;
        let (number, rest) = rest.split_once(" presented at ")?;
        let (size, _) = rest.split_once(' ')?;
        let (w, h) = size.split_once('x')?;
        let vec = |key: &str| -> Option<glam::Vec3> {
            let v: Vec<f32> = line
                .split_once(&format!("{key} ["))?
                .1
                .split(']')
                .next()?
                .split(',')
                .map(|x| x.trim().parse().ok())
                .collect::<Option<_>>()?;
            (v.len() == 3).then(|| glam::Vec3::from_slice(&v))
        };
        Some(Frame {
            number: number.trim().parse().ok()?,
            size: (w.parse().ok()?, h.parse().ok()?),
            position: vec("camera at")?,
        })
    }
}

/// The viewer's log filter for the window tests: its info lines and its per-frame lines.
const VIEWER_LOG: &str = "warn,voxgi::app=debug";

/// How long a session waits for a log line.
const LOG_WAIT: Duration = Duration::from_secs(90);

impl EditSession {
    fn start(args: &[&str]) -> Self {
        Self::start_with(args, |_| {})
    }

    fn start_with(args: &[&str], setup: impl FnOnce(&mut Command)) -> Self {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_voxgi"));
        cmd.args(args)
            .args(fixed_size(args))
            .env_remove("WAYLAND_DISPLAY")
            .env("RUST_LOG", VIEWER_LOG)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        setup(&mut cmd);
        let mut child = cmd.spawn().expect("run the voxgi binary");
        let stderr = child.stderr.take().expect("piped stderr");
        let (tx, lines) = std::sync::mpsc::channel::<String>();
        let reader = std::thread::spawn(move || {
            use std::io::BufRead;
            for line in std::io::BufReader::new(stderr)
                .lines()
                .map_while(Result::ok)
            {
                let _ = tx.send(line);
            }
        });
        // This viewer's window (winit sets `_NET_WM_PID`), not one a failed test left behind.
        let pid = child.id().to_string();
        let window = xdotool(&[
            "search",
            "--sync",
            "--onlyvisible",
            "--pid",
            &pid,
            "--name",
            "^voxgi$",
        ]);
        let window = window.lines().next().expect("a window id").to_string();
        xdotool(&["windowfocus", "--sync", &window]);
        Self {
            child,
            window,
            lines,
            reader: Some(reader),
            log: String::new(),
            frame: None,
        }
    }

    /// Takes one line into the log (a frame line into `frame`); whether it contains `want`.
    fn take(&mut self, line: &str, want: &str) -> bool {
        match Frame::parse(line) {
            Some(f) => self.frame = Some(f),
            None => {
                self.log += line;
                self.log.push('\n');
            }
        }
        !want.is_empty() && line.contains(want)
    }

    /// The next log line for which `done` holds, within [`LOG_WAIT`]; `what` names it in the
    /// failure.
    fn wait_until(&mut self, what: &str, mut done: impl FnMut(&mut Self, &str) -> bool) -> String {
        let started = Instant::now();
        loop {
            let left = LOG_WAIT.saturating_sub(started.elapsed());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.take(&line, "");
                    if done(self, &line) {
                        return line;
                    }
                }
                Err(_) => {
                    let _ = self.child.kill();
                    panic!(
                        "{what} not in the viewer's log within {LOG_WAIT:?} (last frame \
                         {:?}):\n{}",
                        self.frame, self.log
                    )
                }
            }
        }
    }

    /// The next log line containing `want`.
    fn wait_for(&mut self, want: &str) -> String {
        self.wait_until(&format!("`{want}`"), |_, line| line.contains(want))
    }

    /// Reads what the viewer logged so far without waiting; the last line containing `want`
    /// among it, if any.
    fn drain(&mut self, want: &str) -> Option<String> {
        let mut last = None;
        while let Ok(line) = self.lines.try_recv() {
            if self.take(&line, want) {
                last = Some(line);
            }
        }
        last
    }

    /// Waits until `n` whole frames began after this call (the frame in progress when it was
    /// made may have missed an input just sent): the input has been seen and drawn. Returns
    /// the last frame.
    fn frames(&mut self, n: u64) -> Frame {
        self.drain("");
        let target = self.frame.map_or(0, |f| f.number) + 1 + n;
        self.wait_until(&format!("frame {target}"), |s, _| {
            s.frame.is_some_and(|f| f.number >= target)
        });
        self.frame.expect("a frame was logged")
    }

    /// `first` or the last line containing `want` logged since, once the log has shown no
    /// new `want` line for `quiet` whole frames (the panel may lay out again in the frames
    /// after a change: the GPU-time table fills in, a combo opens).
    fn settled(&mut self, first: String, want: &str, quiet: u64) -> String {
        let mut last = first;
        loop {
            // A `want` line already waiting counts too: the panel lays out a frame after the
            // state it logs (the last wheel step's offset, then the button where it moved).
            if let Some(line) = self.drain(want) {
                last = line;
            }
            let target = self.frame.map_or(0, |f| f.number) + 1 + quiet;
            let mut moved = None;
            self.wait_until(&format!("frame {target}"), |s, line| {
                if line.contains(want) {
                    moved = Some(line.to_owned());
                }
                s.frame.is_some_and(|f| f.number >= target)
            });
            match moved {
                Some(line) => last = line,
                None => return last,
            }
        }
    }

    /// The line containing `want` if the viewer logs it within `n` frames from now.
    fn within_frames(&mut self, want: &str, n: u64) -> Option<String> {
        self.within_frames_where(n, |line| line.contains(want))
    }

    /// A line for which `wanted` holds if the viewer logged one not yet read (the last of
    /// them) or logs one within `n` frames from now.
    fn within_frames_where(&mut self, n: u64, wanted: impl Fn(&str) -> bool) -> Option<String> {
        let mut found = None;
        while let Ok(line) = self.lines.try_recv() {
            self.take(&line, "");
            if wanted(&line) {
                found = Some(line);
            }
        }
        if found.is_some() {
            return found;
        }
        let target = self.frame.map_or(0, |f| f.number) + 1 + n;
        self.wait_until(&format!("a wanted line or frame {target}"), |s, line| {
            if wanted(line) {
                found = Some(line.to_owned());
            }
            found.is_some() || s.frame.is_some_and(|f| f.number >= target)
        });
        found
    }

    /// Moves the pointer to window pixel `[x, y]` and waits until a frame has seen it (egui
    /// takes a press where the pointer was last seen).
    fn hover(&mut self, [x, y]: [f32; 2]) {
        let (x, y) = (format!("{}", x.round()), format!("{}", y.round()));
        xdotool(&["mousemove", "--window", &self.window, &x, &y]);
        self.frames(1);
    }

    fn click(&mut self, at: [f32; 2]) {
        self.hover(at);
        xdotool(&["click", "1"]);
    }

    /// Presses the left button at `from` and drags by `steps` × (`dx`, `dy`) pixels, a frame
    /// per step: egui's drag delta is the pointer's motion over a frame, so a frame that saw
    /// the jump to `from`, the press and the first step at once would add the jump to the drag.
    fn drag(&mut self, from: [f32; 2], (dx, dy): (i32, i32), steps: u32) {
        self.hover(from);
        xdotool(&["mousedown", "1"]);
        self.frames(1);
        for _ in 0..steps {
            xdotool(&["mousemove_relative", "--", &dx.to_string(), &dy.to_string()]);
            self.frames(1);
        }
        xdotool(&["mouseup", "1"]);
    }

    fn key(&self, key: &str) {
        xdotool(&["windowfocus", "--sync", &self.window]);
        xdotool(&["key", key]);
    }

    /// Holds `key` down until the logged camera satisfies `arrived` (the fly camera integrates
    /// frame times, so how far it gets in a fixed time depends on the machine's load).
    fn hold_until(&mut self, key: &str, what: &str, arrived: impl Fn(&Frame) -> bool) -> Frame {
        xdotool(&["windowfocus", "--sync", &self.window]);
        xdotool(&["keydown", key]);
        self.wait_until(what, |s, _| s.frame.as_ref().is_some_and(&arrived));
        xdotool(&["keyup", key]);
        self.frames(1)
    }

    /// Escape, then the exit status (0: no validation message, teardown included).
    fn finish(self) -> String {
        self.finish_with_stdout().0
    }

    /// Escape, then the exit status, the log and what the viewer printed.
    fn finish_with_stdout(self) -> (String, String) {
        self.key("Escape");
        self.wait_for_exit()
    }

    /// Waits for the viewer to exit (asked by the test), reads the rest of its log and
    /// output and asserts the exit status 0: no validation message, teardown included.
    fn wait_for_exit(mut self) -> (String, String) {
        wait_for_exit(&mut self.child, "the session");
        let mut stdout = String::new();
        if let Some(mut out) = self.child.stdout.take() {
            use std::io::Read;
            let _ = out.read_to_string(&mut stdout);
        }
        let status = self.child.wait().expect("the viewer's status");
        if let Some(r) = self.reader.take() {
            r.join().expect("the log reader");
        }
        self.drain("");
        assert!(
            status.success(),
            "voxgi --validate view failed ({status}):\n{}",
            self.log
        );
        assert!(!self.log.contains("panicked"), "{}", self.log);
        (std::mem::take(&mut self.log), stdout)
    }
}

impl Drop for EditSession {
    /// A test that fails midway stops its viewer: left running, its window would take the
    /// next test's input.
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// `[x, y]` after `key` in a log line (`… x [301.5, 150.0] …`).
fn logged_point(line: &str, key: &str) -> [f32; 2] {
    let rest = line
        .split_once(&format!("{key} ["))
        .unwrap_or_else(|| panic!("no `{key} [..]` in {line}"))
        .1;
    let nums: Vec<f32> = rest
        .split(']')
        .next()
        .unwrap_or("")
        .split(',')
        .map(|x| x.trim().parse().expect("a number"))
        .collect();
    [nums[0], nums[1]]
}

/// Where the scene lies in the window (`edit: scene viewport at [x, 0] size [w, h] px`).
fn viewport(line: &str) -> [f32; 4] {
    let [x, y] = logged_point(line, "at");
    let [w, h] = logged_point(line, "size");
    [x, y, w, h]
}

/// Window pixel of world point `p` seen by `camera` in `viewport` (Vulkan clip space: y down).
fn project(camera: &voxgi::scene::Camera, viewport: [f32; 4], p: glam::Vec3) -> [f32; 2] {
    let clip = camera.view_proj(viewport[2] / viewport[3]) * p.extend(1.0);
    [
        viewport[0] + (clip.x / clip.w * 0.5 + 0.5) * viewport[2],
        viewport[1] + (clip.y / clip.w * 0.5 + 0.5) * viewport[3],
    ]
}

/// Renders `scene` headless at the screenshot's size with `extra` flags.
fn render_headless(
    dir: &Path,
    scene: &Path,
    extra: &[&str],
    (w, h): (u32, u32),
) -> image::RgbaImage {
    let out_png = dir.join(format!(
        "{}-render.png",
        scene
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy())
    ));
    let (w, h) = (w.to_string(), h.to_string());
    let mut args = vec![
        "--validate",
        "render",
        scene.to_str().expect("utf-8 path"),
        "--width",
        &w,
        "--height",
        &h,
        "-o",
        out_png.to_str().expect("utf-8 path"),
    ];
    args.extend(extra);
    let out = voxgi(&args);
    assert_success(&out, &format!("voxgi render {}", scene.display()));
    load(&out_png)
}

fn max_channel_diff(a: &image::RgbaImage, b: &image::RgbaImage) -> u8 {
    a.pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |c| p.0[c].abs_diff(q.0[c])))
        .max()
        .unwrap_or(0)
}

/// Click the tall block (the GPU pick selects it), drag its x handle with the mouse (it
/// becomes dynamic and is re-voxelized where it goes), switch to rotation with `2` and turn it
/// about Y with the mouse, Ctrl+S, F12, Escape: the saved file holds the move and the turn
/// (no scale), and the voxel view the viewer showed is what a headless render of the saved
/// file shows. Against the scene before the edit, the voxels changed only where the block was
/// or went.
#[test]
fn viewer_picks_drags_revoxelizes_and_saves_an_object_with_real_mouse_events() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("edit-object");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, include_str!("../assets/scenes/cornell.toml")).expect("write");
    let (saved, shot) = (dir.join("saved.toml"), dir.join("shot.png"));
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        scene.to_str().expect("utf-8 path"),
        "--gi",
        "none",
        "--debug",
        "voxels",
        "--width",
        "560",
        "--height",
        "320",
        "--save",
        saved.to_str().expect("utf-8 path"),
        "--screenshot",
        shot.to_str().expect("utf-8 path"),
    ]);
    let vp = viewport(&s.wait_for("edit: scene viewport at"));
    let original = voxgi::scene::Scene::load(&scene).expect("the scene loads");
    let block = original.objects[2].aabb_at(0.0);
    s.click(project(&original.camera, vp, block.center()));
    let selected = s.wait_for("edit: selected object");
    assert!(
        selected.contains("selected object 2 \"tall_block\""),
        "the click on the tall block selected: {selected}"
    );
    // Screen-left is world +X for a camera looking along +Z: the x handle points left.
    let tip = logged_point(&selected, "x");
    s.drag(tip, (-4, 0), 5);
    s.wait_for("edit: object 2 at translate");
    s.key("2");
    let rotate = s.wait_for("Rotate handles");
    s.drag(logged_point(&rotate, "y"), (4, 0), 5);
    s.wait_for("edit: object 2 at translate");
    s.key("ctrl+s");
    s.wait_for("saved scene to");
    s.key("F12");
    s.wait_for("wrote");
    let log = s.finish();
    assert!(!log.contains("Validation"), "{log}");

    let text = std::fs::read_to_string(&saved).expect("the saved scene");
    let back = voxgi::scene::Scene::load(&saved).expect("the saved scene loads");
    // Turning about the block's centre: its centre moved by the drag along x only.
    let centre = |o: &voxgi::scene::Object| o.aabb_at(0.0).center();
    let moved = centre(&back.objects[2]) - block.center();
    assert!(
        moved.x > 0.005 && moved.y.abs() < 1e-5 && moved.z.abs() < 1e-5,
        "the centre moved by {moved}:\n{text}"
    );
    // A turn about world Y: rotate_deg = [0, θ, 0] up to rounding, θ ≠ 0.
    let turned = voxgi::scene::euler_xyz_deg(back.objects[2].transform.rotation);
    assert!(
        turned.y.abs() > 1.0 && turned.x.abs() < 1e-3 && turned.z.abs() < 1e-3,
        "turned by {turned} degrees:\n{text}"
    );
    assert_eq!(back.objects[2].transform.scale, glam::Vec3::ONE);
    assert_eq!(back.objects[..2], original.objects[..2]);
    assert_eq!(back.lights, original.lights);
    assert!(
        text.contains("# Floor, ceiling and back wall white"),
        "{text}"
    );
    assert!(
        text.contains("rotate_deg") && !text.contains("scale"),
        "{text}"
    );

    let img = load(&shot);
    let size = img.dimensions();
    let debug = ["--gi", "none", "--debug", "voxels"];
    let after = render_headless(&dir, &saved, &debug, size);
    let diff = max_channel_diff(&img, &after);
    assert!(
        diff <= 1,
        "the viewer's voxels differ from a render of the saved scene by {diff}/255"
    );
    // Against the voxels before the move: changes only where the block was or is now, i.e.
    // inside the projection of the union of its old and new bounds, widened by 2 pixels (a
    // voxel is 0.56 m / 128 = 4.4 mm, under a pixel here; conservative voxelization adds one
    // voxel around each triangle; the debug view's rays enter a voxel up to a pixel aside).
    let before = render_headless(&dir, &scene, &debug, size);
    let union = block.union(back.objects[2].aabb_at(0.0));
    let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
    for k in 0..8 {
        let c = glam::Vec3::new(
            if k & 1 == 0 { union.min.x } else { union.max.x },
            if k & 2 == 0 { union.min.y } else { union.max.y },
            if k & 4 == 0 { union.min.z } else { union.max.z },
        );
        // In the screenshot's pixels (the viewport's own, from 0).
        let p = project(&original.camera, [0.0, 0.0, vp[2], vp[3]], c);
        for i in 0..2 {
            lo[i] = lo[i].min(p[i] - 2.0);
            hi[i] = hi[i].max(p[i] + 2.0);
        }
    }
    let mut changed = 0;
    for (x, y, p) in img.enumerate_pixels() {
        if max_channel_diff(
            &image::RgbaImage::from_pixel(1, 1, *p),
            &image::RgbaImage::from_pixel(1, 1, *before.get_pixel(x, y)),
        ) > 1
        {
            changed += 1;
            let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
            assert!(
                fx >= lo[0] && fx <= hi[0] && fy >= lo[1] && fy <= hi[1],
                "pixel ({x}, {y}) changed outside the block's old and new bounds {lo:?}–{hi:?}"
            );
        }
    }
    assert!(
        changed > 20,
        "the move changed only {changed} pixels of the voxels"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Click the spot light's marker, drag it along x, add two point lights with Insert, remove
/// the second with Delete (each a new renderer: the shadow views change), click the short
/// block and drag its position x field in the panel, fly forward with W, Ctrl+S, F12, Escape:
/// the saved file has the moved spot (its comment kept), one new point light, the block moved
/// along x and the camera where it flew, and its headless render is what the viewer showed.
/// (1000 pixels high: the panel does not scroll, and the Edit section comes after the GPU-time
/// table, the stereo and projection controls and the frame-time graph.)
#[test]
fn viewer_edits_lights_and_a_field_and_saves_with_real_input_events() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("edit-lights");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, include_str!("../assets/scenes/cornell.toml")).expect("write");
    let (saved, shot) = (dir.join("saved.toml"), dir.join("shot.png"));
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        scene.to_str().expect("utf-8 path"),
        "--gi",
        "none",
        "--width",
        "800",
        "--height",
        "1000",
        "--save",
        saved.to_str().expect("utf-8 path"),
        "--screenshot",
        shot.to_str().expect("utf-8 path"),
    ]);
    let vp = viewport(&s.wait_for("edit: scene viewport at"));
    let original = voxgi::scene::Scene::load(&scene).expect("the scene loads");
    let spot = original.lights[0].position().expect("a spot light");
    s.click(project(&original.camera, vp, spot));
    let selected = s.wait_for("edit: selected light");
    assert!(selected.contains("selected light 0 (spot 0)"), "{selected}");
    s.drag(logged_point(&selected, "x"), (-4, 0), 5);
    s.wait_for("edit: light 0 now");
    s.key("Insert");
    s.wait_for("edit: added light 1");
    s.wait_for("new renderer");
    s.key("Insert");
    s.wait_for("edit: added light 2");
    s.wait_for("new renderer");
    s.key("Delete");
    s.wait_for("edit: removed light 2");
    s.wait_for("new renderer");
    let short = original.objects[1].aabb_at(0.0).center();
    s.click(project(&original.camera, vp, short));
    let selected = s.wait_for("edit: selected object");
    assert!(
        selected.contains("selected object 1 \"short_block\""),
        "{selected}"
    );
    let want = "edit: position field x at";
    let first = s.wait_for(want);
    let field = logged_point(&s.settled(first, want, 3), "at");
    // egui's drag value: +5 × 6 points at 0.005 × the scene's diagonal per point.
    s.drag(field, (6, 0), 5);
    // Held until the camera is 5 cm further in (frames take their time on lavapipe).
    let from = s.frames(1);
    s.hold_until("w", "the camera 5 cm forward", |f| {
        f.position.z - from.position.z > 0.05
    });
    s.key("ctrl+s");
    s.wait_for("saved scene to");
    s.key("F12");
    s.wait_for("wrote");
    s.finish();

    let text = std::fs::read_to_string(&saved).expect("the saved scene");
    let back = voxgi::scene::Scene::load(&saved).expect("the saved scene loads");
    assert_eq!(back.lights.len(), 2, "{text}");
    let moved = back.lights[0].position().expect("the spot") - spot;
    assert!(
        moved.x > 0.005 && moved.y == 0.0 && moved.z == 0.0,
        "the spot moved by {moved}:\n{text}"
    );
    assert!(back.lights[1].is_point(), "{text}");
    assert!(
        text.contains("# A spot light just under the ceiling"),
        "{text}"
    );
    let field_moved = back.objects[1].transform.translate - original.objects[1].transform.translate;
    assert!(
        field_moved.x > 0.01 && field_moved.y == 0.0 && field_moved.z == 0.0,
        "the position field moved the short block by {field_moved}:\n{text}"
    );
    assert_eq!(back.objects[0], original.objects[0]);
    assert_eq!(back.objects[2], original.objects[2]);
    // W flies along the view (+Z): the saved camera stands further in, looking the same way.
    let flew = back.camera.position - original.camera.position;
    assert!(
        flew.z > 0.01 && flew.x.abs() < 1e-6 && flew.y.abs() < 1e-6,
        "the camera flew by {flew}:\n{text}"
    );
    assert!(back.camera.forward.distance(original.camera.forward) < 1e-6);
    assert!(!text.contains("target ="), "{text}");

    let img = load(&shot);
    let flags = ["--gi", "none"];
    let after = render_headless(&dir, &saved, &flags, img.dimensions());
    let diff = max_channel_diff(&img, &after);
    assert!(
        diff <= 1,
        "the viewer's frame differs from a render of the saved scene by {diff}/255"
    );
    let before = render_headless(&dir, &scene, &flags, img.dimensions());
    assert!(
        max_channel_diff(&img, &before) > 16,
        "the light edits did not change the image"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The viewer's screenshot `shot` after `frames` TAA frames of `scene` (at least 2) equals
/// `voxgi render --taa --taa-frames FRAMES` within one 8-bit step and differs from the render
/// without TAA by more than 8/255 (something was blended).
fn assert_taa_screenshot_is_the_render(dir: &Path, scene: &Path, shot: &Path, frames: u32) {
    assert!(frames >= 2, "only {frames} TAA frame(s) blended");
    let img = load(shot);
    let size = img.dimensions();
    let taa_frames = frames.to_string();
    let taa = render_headless(
        dir,
        scene,
        &["--gi", "none", "--taa", "--taa-frames", &taa_frames],
        size,
    );
    let diff = max_channel_diff(&img, &taa);
    assert!(
        diff <= 1,
        "the viewer's {frames} TAA frames differ from `voxgi render --taa --taa-frames \
         {frames}` by up to {diff}/255"
    );
    let aliased = render_headless(dir, scene, &["--gi", "none"], size);
    let control = max_channel_diff(&img, &aliased);
    eprintln!(
        "{size:?}: {frames} TAA frames; against render --taa {diff}/255, without TAA {control}/255"
    );
    assert!(
        control > 8,
        "the TAA image equals the render without TAA (up to {control}/255): nothing blended"
    );
}

/// Abuse (issue #32): scenes that fail to load, given on the command line: a missing file,
/// TOML that does not parse, a value out of range, a mesh that is not there. `voxgi view`
/// refuses each before it opens a window, with a message naming the file (and the line or
/// field), and never panics. (Scenes opened while the viewer runs go through the same loader:
/// `viewer_abuse_opens_scenes_that_fail_while_another_is_shown`.)
#[test]
fn viewer_abuse_refuses_scenes_that_fail_to_load_naming_the_file() {
    let dir = scratch_dir("abuse-load");
    let cornell = include_str!("../assets/scenes/cornell.toml");
    let write = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write the scene");
        path
    };
    let cases = [
        (dir.join("no-such-scene.toml"), vec!["no-such-scene.toml"]),
        (write("broken.toml", "[camera\n"), vec!["broken.toml:1:"]),
        (
            write(
                "wide.toml",
                &cornell.replacen("fov_y_deg = ", "fov_y_deg = 400.0 # ", 1),
            ),
            vec!["wide.toml", "fov_y_deg"],
        ),
        (
            write(
                "no_mesh.toml",
                &format!("{cornell}\n[[objects]]\nname = \"gone\"\nmesh = \"gone.obj\"\n"),
            ),
            vec!["gone.obj"],
        ),
    ];
    for (scene, names) in cases {
        let out = voxgi(&[
            "--validate",
            "view",
            scene.to_str().expect("utf-8 path"),
            "--width",
            "320",
            "--height",
            "240",
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && !stderr.contains("panicked"),
            "voxgi view {} ({}):\n{stderr}",
            scene.display(),
            out.status
        );
        for name in names {
            assert!(
                stderr.contains(name),
                "the message does not name {name}:\n{stderr}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Abuse (issue #32): 200 presses of G (the viewer's key for the next GI method), in bursts
/// of 33 presses 5 ms apart (and one of 2), a frame between bursts. Presses between two
/// frames take effect together in the next frame, and no burst comes back to the method it
/// started from, so each burst makes at least one new renderer (while the last one's frames may be in flight). The
/// viewer must see every press (it logs each), make those renderers, end on the method 200
/// presses away, show it (with `none` there, exactly what `voxgi render` writes) and exit
/// clean: no validation message, teardown included.
#[test]
fn viewer_abuse_switches_the_gi_method_200_times() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("abuse-switch");
    let shot = dir.join("shot.png");
    let shot_arg = shot.to_str().expect("utf-8 path");
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        "--gi",
        "none",
        "--width",
        "320",
        "--height",
        "240",
        "--screenshot",
        shot_arg,
    ]);
    s.frames(1);
    xdotool(&["windowfocus", "--sync", &s.window]);
    const PRESSES: usize = 200;
    const BURST: usize = 33;
    let all = voxgi::gi::GiMethod::ALL;
    let mut seen = 0;
    let mut bursts = 0;
    while seen < PRESSES {
        let burst = BURST.min(PRESSES - seen);
        assert!(
            !burst.is_multiple_of(all.len()),
            "a burst comes back to its method"
        );
        bursts += 1;
        xdotool(&[
            "key",
            "--repeat",
            &burst.to_string(),
            "--repeat-delay",
            "5",
            "g",
        ]);
        let want = seen + burst;
        s.wait_until(&format!("{want} presses of G"), |_, line| {
            seen += usize::from(line.contains("key G: indirect light"));
            seen == want
        });
        s.frames(1);
    }
    let last = all[PRESSES % all.len()];
    // The frame after the last press has the renderer for it.
    s.frames(2);
    s.key("F12");
    s.wait_for(&format!("wrote {shot_arg}"));
    let log = s.finish();
    let renderers = log.matches("new renderer").count();
    eprintln!("{PRESSES} presses of G made {renderers} renderers");
    let current = log
        .lines()
        .filter_map(|l| l.split_once("indirect light: ").map(|(_, r)| r))
        .next_back()
        .unwrap_or_else(|| panic!("no renderer logged:\n{log}"));
    assert!(
        current.starts_with(last.name()),
        "after {PRESSES} presses the renderer is for {current}, not {}",
        last.name()
    );
    assert!(
        renderers >= bursts,
        "{bursts} bursts of G made {renderers} renderer(s):\n{log}"
    );
    let img = load(&shot);
    assert_not_blank(&img);
    if last == voxgi::gi::GiMethod::None {
        assert_matches_render(&img, &dir);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Abuse (issue #32): the window resized to 1×1 and back, then wider than the device draws
/// (16400 px: lavapipe's largest image and viewport are 16384, and an X window may be 32767)
/// and back. At 1×1 the viewer presents 1×1 frames; past the limit it says so, naming the
/// size and the limit, draws nothing (no swapchain can have the window's size) and keeps
/// everything; back at 320×240 it shows exactly what `voxgi render` writes, and exits clean
/// (no validation message, teardown included). 8 px high, so the oversized window asks
/// little memory of anyone.
#[test]
fn viewer_abuse_resizes_to_1x1_and_past_the_device_limit() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("abuse-resize");
    let shot = dir.join("shot.png");
    let shot_arg = shot.to_str().expect("utf-8 path");
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        "--gi",
        "none",
        "--width",
        "320",
        "--height",
        "240",
        "--screenshot",
        shot_arg,
    ]);
    s.frames(1);
    let resize = |s: &mut EditSession, (w, h): (u32, u32)| {
        // No window manager here: the size is applied as asked.
        xdotool(&["windowsize", &s.window, &w.to_string(), &h.to_string()]);
    };
    let presented = |s: &mut EditSession, size: (u32, u32)| {
        s.wait_until(&format!("a frame at {}x{}", size.0, size.1), |s, _| {
            s.frame.is_some_and(|f| f.size == size)
        });
    };
    resize(&mut s, (1, 1));
    presented(&mut s, (1, 1));
    s.frames(2);
    resize(&mut s, (320, 240));
    presented(&mut s, (320, 240));
    resize(&mut s, (16400, 8));
    let refused = s.wait_for("larger than this device draws");
    assert!(
        refused.contains("16400x8 px") && refused.contains("16384x16384 px at most"),
        "{refused}"
    );
    resize(&mut s, (320, 240));
    s.wait_for("the window is 320x240 px again: drawing");
    presented(&mut s, (320, 240));
    s.key("F12");
    s.wait_for(&format!("wrote {shot_arg}"));
    let log = s.finish();
    assert!(!log.contains("Validation"), "{log}");
    let img = load(&shot);
    assert_eq!(img.height(), 240);
    assert_matches_render(&img, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Abuse (issue #32): the window closed while a slow frame is in flight. The path tracer
/// (4 rays, 1 bounce) takes a second or more per frame on lavapipe; right after the first
/// frame was presented (the second is then recording or on the GPU), the window manager's
/// close (Alt+F4 in openbox: WM_DELETE_WINDOW, as the title bar's button sends) arrives. The
/// viewer finishes the frames in flight and exits 0: no validation message, teardown
/// included, no panic; its log says it waited for at least one frame in flight. Then the window destroyed outright by another client (xdotool's
/// `windowclose`: no request, the X window is simply gone mid-frame): the viewer says so and
/// exits 0 as well, without asking the dead window anything.
#[test]
fn viewer_abuse_closes_cleanly_mid_frame() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("abuse-close");
    let _wm = start_window_manager(&dir);
    for destroy in [false, true] {
        let mut s = EditSession::start(&[
            "--validate",
            "view",
            "--gi",
            "pathtrace",
            "--gi-rays",
            "4",
            "--gi-bounces",
            "1",
            "--width",
            "320",
            "--height",
            "240",
        ]);
        s.wait_until("the first frame", |s, _| s.frame.is_some());
        if destroy {
            xdotool(&["windowclose", &s.window]);
        } else {
            xdotool(&["windowactivate", "--sync", &s.window]);
            xdotool(&["key", "alt+F4"]);
        }
        let (log, _) = s.wait_for_exit();
        assert!(!log.contains("Validation"), "{log}");
        if destroy {
            assert!(log.contains("the window was destroyed: exiting"), "{log}");
        }
        // The close found frames submitted whose completion the frame loop had not seen,
        // and waited for them before releasing anything. (Whether they were still running:
        // on lavapipe never, by then: Mesa's `wsi_common_queue_present` waits for the
        // frame's fence on a software device before it presents, and a close arrives
        // between frames, after their presentation. A GPU with an asynchronous present
        // reports the running ones.)
        let closing = log
            .lines()
            .find(|l| l.contains("closing: waiting for "))
            .unwrap_or_else(|| panic!("the viewer did not log its close:\n{log}"));
        let count = |after: &str| -> usize {
            closing
                .split_once(after)
                .and_then(|(_, r)| r.split(' ').next())
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("no count after `{after}` in `{closing}`"))
        };
        let (waited, running) = (count("waiting for "), count(" ("));
        eprintln!("destroy {destroy}: {waited} frames in flight at close, {running} running");
        assert!(waited >= 1, "destroy {destroy}: {closing}");
        assert!(running <= waited, "destroy {destroy}: {closing}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Types `text` into the panel's path field and presses Enter: a click focuses the field,
/// Ctrl+A selects what it held, the typing replaces it.
fn open_from_panel(s: &mut EditSession, field: [f32; 2], text: &str) {
    s.click(field);
    s.frames(1);
    xdotool(&["key", "ctrl+a"]);
    xdotool(&["type", "--delay", "20", text]);
    s.frames(1);
    xdotool(&["key", "Return"]);
}

/// Abuse (issue #32): scenes that fail to load, opened from the panel's "Open scene" section while
/// the built-in Cornell box is shown: a missing file, TOML that does not parse, a value out of
/// range. Each is refused with the loader's message naming the file (and the line or field)
/// in the log (and the panel), and the scene shown stays exactly as it was: F12 then equals
/// `voxgi render`. Then a good scene (the box seen with a narrower lens) opens: its
/// screenshot equals `voxgi render` of that file. Validation clean, teardown included.
#[test]
fn viewer_abuse_opens_scenes_that_fail_while_another_is_shown() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("abuse-open");
    let cornell = include_str!("../assets/scenes/cornell.toml");
    let write = |name: &str, text: &str| {
        std::fs::write(dir.join(name), text).expect("write the scene");
    };
    write("broken.toml", "[camera\n");
    write(
        "wide.toml",
        &cornell.replacen("fov_y_deg = ", "fov_y_deg = 400.0 # ", 1),
    );
    write(
        "narrow.toml",
        &cornell.replacen("fov_y_deg = ", "fov_y_deg = 30.0 # ", 1),
    );
    let shot = dir.join("shot.png");
    let shot_arg = shot.to_str().expect("utf-8 path");
    let (w, h) = (480.0, 480.0);
    // Relative paths, as a person types them: the viewer runs in the scratch folder.
    let mut s = EditSession::start_with(
        &[
            "--validate",
            "view",
            "--gi",
            "none",
            "--width",
            "480",
            "--height",
            "480",
            "--screenshot",
            shot_arg,
        ],
        |cmd| {
            cmd.current_dir(&dir);
        },
    );
    let first = s.wait_for("panel: scrolled");
    s.settled(first, "panel: scrolled", 3);
    let field = scroll_panel_to(&mut s, "open path", h);
    let cases = [
        ("no-such-scene.toml", vec!["no-such-scene.toml"]),
        ("broken.toml", vec!["broken.toml:1:"]),
        ("wide.toml", vec!["wide.toml", "fov_y_deg"]),
    ];
    for (name, wanted) in cases {
        open_from_panel(&mut s, field, name);
        s.wait_for(&format!("{name} not opened: "));
        // The rest of a message over several lines.
        s.frames(1);
        let said = s
            .log
            .rsplit_once(&format!("opening scene {name}"))
            .map_or("", |(_, after)| after)
            .to_owned();
        for want in wanted {
            assert!(
                said.contains(want),
                "the message does not name {want}:\n{said}"
            );
        }
        s.key("F12");
        s.wait_for(&format!("wrote {shot_arg}"));
        let img = load(&shot);
        assert_matches_render(&img, &dir);
    }
    open_from_panel(&mut s, field, "narrow.toml");
    s.wait_for("opened narrow.toml");
    s.frames(2);
    s.key("F12");
    s.wait_for(&format!("wrote {shot_arg}"));
    let (log, stdout) = s.finish_with_stdout();
    assert!(!log.contains("Validation"), "{log}");
    let img = load(&shot);
    let size = img.dimensions();
    assert_eq!(size.1, h as u32);
    let narrow = render_headless(&dir, &dir.join("narrow.toml"), &["--gi", "none"], size);
    let diff = max_channel_diff(&img, &narrow);
    assert!(
        diff <= 1,
        "the opened scene differs from `voxgi render narrow.toml` by up to {diff}/255"
    );
    // Against the scene shown before: something changed.
    let before = render_like_viewer(size.0, size.1, &dir);
    assert!(
        max_channel_diff(&img, &before) > 8,
        "the view did not change"
    );
    // The camera printed at exit is the opened scene's.
    assert!(stdout.contains("camera at exit"), "{stdout}");
    let _ = w;
    let _ = std::fs::remove_dir_all(&dir);
}

/// The viewer makes one renderer before its first frame, for the scene's area right of the
/// panel: not one for the whole window and a second once the panel's width is known (with
/// the path tracer, whose history has the frame's size, that was two renderers).
#[test]
fn viewer_makes_one_renderer_before_its_first_frame() {
    require_display();
    let _display = lock_display();
    let out = voxgi_with(
        &[
            "--validate",
            "view",
            "--gi",
            "pathtrace",
            "--gi-rays",
            "1",
            "--width",
            "320",
            "--height",
            "240",
            "--frames",
            "2",
        ],
        |cmd| {
            cmd.env("RUST_LOG", "warn,voxgi::app=debug");
        },
    );
    assert_success(&out, "voxgi --validate view --gi pathtrace");
    let log = String::from_utf8_lossy(&out.stderr);
    let before_first: Vec<&str> = log
        .lines()
        .take_while(|l| !l.contains("frame 1 presented"))
        .filter(|l| l.contains("new renderer "))
        .collect();
    assert_eq!(before_first.len(), 1, "{log}");
    // 320 px less the panel's 240: the scene's area, 80x240.
    assert!(before_first[0].contains("new renderer 80x240"), "{log}");
    let all = log.lines().filter(|l| l.contains("new renderer ")).count();
    assert_eq!(all, 1, "{log}");
}

/// Abuse (issue #32): a window within the device's largest image (16000 < 16384 px on
/// lavapipe) whose frame does not fit the device's memory: 16000×16000 is 1 GiB per
/// swapchain image and 4 GiB for the renderer's RGBA32F read-back alone. The viewer counts
/// what that size would allocate before making any of it, refuses it naming the size and
/// the allocation (the message `voxgi render` gives for frames too big), draws nothing at
/// it, and at 320×240 draws again exactly what `voxgi render` writes. Nothing of the big
/// size is allocated, so the test is safe on a small machine.
#[test]
fn viewer_abuse_refuses_a_window_too_big_for_memory() {
    require_display();
    let _display = lock_display();
    let dir = scratch_dir("abuse-memory");
    let shot = dir.join("shot.png");
    let shot_arg = shot.to_str().expect("utf-8 path");
    let mut s = EditSession::start(&[
        "--validate",
        "view",
        "--gi",
        "none",
        "--width",
        "320",
        "--height",
        "240",
        "--screenshot",
        shot_arg,
    ]);
    s.frames(1);
    xdotool(&["windowsize", &s.window, "16000", "16000"]);
    let refused = s.wait_for("more than this device's memory holds");
    assert!(
        refused.contains("16000x16000 px")
            && refused.contains("GiB")
            && refused.contains('`')
            && refused.contains("lower the window's size"),
        "{refused}"
    );
    xdotool(&["windowsize", &s.window, "320", "240"]);
    s.wait_for("the window is 320x240 px again: drawing");
    s.wait_until("a frame at 320x240", |s, _| {
        s.frame.is_some_and(|f| f.size == (320, 240))
    });
    s.key("F12");
    s.wait_for(&format!("wrote {shot_arg}"));
    let log = s.finish();
    assert!(!log.contains("Validation"), "{log}");
    let img = load(&shot);
    assert_matches_render(&img, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}
