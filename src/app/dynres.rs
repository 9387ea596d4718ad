//! Dynamic resolution: the internal render scale that holds the frame budget
//! (`post.frame_budget_ms`, `docs/design/dynamic-resolution.md`).
//!
//! The controller sees one measurement per presented frame: the GPU time of a finished frame,
//! the sum of its passes' timestamp pairs (the frame loop reads them back two frames late),
//! so it measures what the scale changes and not the CPU's share or the wait for the display.
//! Its scale is a whole number of eighths of the window's size per axis: a new scale costs
//! a new renderer (the GI histories have the frame's size), so it must change seldom, and
//! quantizing it keeps the number of distinct sizes small.
//!
//! - **Down at once.** A frame over budget predicts the scale that fits, assuming the time
//!   scales with the pixel count (s²), and jumps there: on lavapipe a full-size frame takes
//!   seconds, and stepping an eighth at a time would take minutes.
//! - **Up with hysteresis.** To the largest scale whose prediction stays under
//!   [`UP_FRACTION`] of the budget, and only when that is at least one eighth up, so a frame
//!   that just fits does not go up and come back.
//!   With a fixed cost per frame (shadow maps, the panel) the s² prediction overestimates
//!   the time of a larger scale and underestimates that of a smaller one: up steps are
//!   cautious and a down jump that was too optimistic is followed by a second one.
//! - **Each measurement at its own scale.** The viewer passes the scale a measured frame was
//!   recorded at: the frames still in flight when the scale changed are not mistaken for
//!   frames of the new scale (they are left out), and a renderer's first frame (one-time
//!   work: voxelization, cleared histories) is not measured at all.
//! - **Refine.** After `refine_frames` frames without camera motion the scene renders at the
//!   full size (the image converges there); the first moving frame returns to the scale that
//!   held the budget while moving, without measuring again.
//! - **The GI follows the scale** (`post.dynamic_gi`, [`ScaleController::gi`]): below the
//!   full size the voxel methods trace [`MOVING_GI_RAYS`] per pixel, and the scene's count
//!   once refined. A ray count is baked into the renderer like the size, and it changes only
//!   together with the scale, so it costs no renderer of its own. The viewer also turns
//!   temporal accumulation on ([`viewer_gi`]), which makes one ray per pixel and frame
//!   converge while the camera stands still.

use crate::gi::GiSettings;
use crate::scene::{DynamicResolution, MOVING_GI_RAYS};

/// Scales are whole eighths of the window's size per axis.
pub const STEPS: u32 = 8;
/// A step up only when the next scale's predicted time is under this share of the budget.
pub const UP_FRACTION: f64 = 0.7;
/// A down jump aims at this share of the budget, leaving room for the fixed costs the s²
/// prediction leaves out.
pub const DOWN_TARGET: f64 = 0.9;
/// The median of this many measurements decides a step (one frame over twice the budget
/// decides alone).
pub const WINDOW: usize = 3;

/// Why the scale changed, for the log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// The viewer starts at the smallest scale.
    Start,
    /// Over budget: down to this many eighths.
    Down { gpu_ms: f64 },
    /// Well under budget: up.
    Up { gpu_ms: f64 },
    /// The camera stood still: full size.
    Refine,
    /// The camera moves again: back to the moving scale.
    Moving,
    /// The settings changed (budget, minimum, on or off).
    Settings,
}

/// The scale chosen per frame; see the module's notes.
#[derive(Clone, Debug)]
pub struct ScaleController {
    settings: DynamicResolution,
    /// The scale that holds the budget while the camera moves, eighths.
    moving: u32,
    /// Rendering at the full size because the camera stood still.
    refined: bool,
    still_frames: u32,
    /// GPU times of frames at the current moving scale since it was chosen.
    samples: Vec<f64>,
}

impl ScaleController {
    /// Starts at the smallest scale: its first frames are the cheapest, and a device that
    /// holds the budget at the full size is there a few frames later (up jumps by
    /// prediction). Starting at the full size cost lavapipe two minutes under load before
    /// the first smaller frame: two full frames in flight and one measured, 20 s each.
    pub fn new(settings: DynamicResolution) -> Self {
        let mut c = Self {
            settings,
            moving: STEPS,
            refined: false,
            still_frames: 0,
            samples: Vec::new(),
        };
        c.moving = c.min_steps();
        c
    }

    /// The smallest scale, eighths (the setting rounded up to an eighth).
    fn min_steps(&self) -> u32 {
        ((self.settings.min_scale * STEPS as f32).ceil() as u32).clamp(1, STEPS)
    }

    /// The scale in eighths of the window's size per axis.
    pub fn steps(&self) -> u32 {
        if !self.settings.on() || self.refined {
            STEPS
        } else {
            self.moving
        }
    }

    /// The GI settings the current scale renders with, from the panel's (`base`): see
    /// [`gi_at_scale`].
    pub fn gi(&self, base: GiSettings) -> GiSettings {
        gi_at_scale(base, self.steps(), &self.settings)
    }

    /// The size TAA upsampling resolves the `internal` frame into (`post.upscale = "taa"`):
    /// the scene's `area` while the frame is smaller, else `None` (full size: the frame is
    /// the area's as `voxgi render` writes it; bilinear: the present pass blits).
    pub fn upsample_to(&self, internal: (u32, u32), area: (u32, u32)) -> Option<(u32, u32)> {
        let taa = self.settings.upscale == crate::scene::Upscale::Taa;
        (taa && self.settings.on() && internal != area).then_some(area)
    }

    /// The internal size for a `size` area (each axis at least one pixel).
    pub fn internal_size(&self, (w, h): (u32, u32)) -> (u32, u32) {
        scaled_size((w, h), self.steps())
    }

    /// New settings from the panel; `Some` when they change the scale.
    pub fn set(&mut self, settings: DynamicResolution) -> Option<Change> {
        if settings == self.settings {
            return None;
        }
        let before = self.steps();
        self.settings = settings;
        self.moving = self.moving.clamp(self.min_steps(), STEPS);
        self.samples.clear();
        (self.steps() != before).then_some(Change::Settings)
    }

    /// One presented frame: `measured`, the GPU time of the frame that finished and the scale
    /// (eighths) it was recorded at (`None` when there is none to measure), and whether the
    /// camera stood still since the last frame. `Some` when the scale changes for the next
    /// frame.
    pub fn observe(&mut self, measured: Option<(f64, u32)>, still: bool) -> Option<Change> {
        if !self.settings.on() {
            return None;
        }
        self.still_frames = if still { self.still_frames + 1 } else { 0 };
        if self.refined {
            if still {
                return None;
            }
            self.refined = false;
            return self.changed(Change::Moving, self.moving != STEPS);
        }
        let refine = self.settings.refine_frames;
        if refine > 0 && self.still_frames >= refine {
            self.refined = true;
            return self.changed(Change::Refine, self.moving != STEPS);
        }
        // Only frames of the scale the decision is about (not the ones in flight at a change).
        let (ms, _) = measured.filter(|&(t, s)| t.is_finite() && t > 0.0 && s == self.moving)?;
        self.samples.push(ms);
        let budget = f64::from(self.settings.frame_budget_ms);
        let far_over = ms > 2.0 * budget;
        if self.samples.len() < WINDOW && !far_over {
            return None;
        }
        let t = if far_over {
            ms
        } else {
            crate::stats::median(&self.samples)
        };
        self.samples.clear();
        let s = f64::from(self.moving);
        // Time ∝ pixels ∝ s²: the scale whose predicted time is `target`.
        let fits = |target: f64| s * (target / t).sqrt();
        if t > budget {
            let to = (fits(DOWN_TARGET * budget).floor() as u32).clamp(self.min_steps(), STEPS);
            let change = to < self.moving;
            self.moving = to.min(self.moving);
            return self.changed(Change::Down { gpu_ms: t }, change);
        }
        let up = (fits(UP_FRACTION * budget).floor() as u32).min(STEPS);
        if up > self.moving {
            self.moving = up;
            return self.changed(Change::Up { gpu_ms: t }, true);
        }
        None
    }

    /// `Some(change)` when the scale changed; the samples of the old one are dropped.
    fn changed(&mut self, change: Change, scale_changed: bool) -> Option<Change> {
        if !scale_changed {
            return None;
        }
        self.samples.clear();
        Some(change)
    }
}

/// The GI settings a frame at `steps` eighths renders with: `base` (the scene's, or the
/// panel's), with [`MOVING_GI_RAYS`] per pixel while the scale is below full and
/// `post.dynamic_gi` is on, for the methods that trace rays per pixel (their spec sweeps
/// `gi.rays`). At the full size, off, or for other methods: `base` itself, so a refined frame
/// is the scene's.
pub fn gi_at_scale(base: GiSettings, steps: u32, settings: &DynamicResolution) -> GiSettings {
    let traces_rays = base.method.spec().sweep_keys.contains(&"gi.rays");
    if !settings.dynamic_gi || steps >= STEPS || !traces_rays {
        return base;
    }
    GiSettings {
        rays: base.rays.min(MOVING_GI_RAYS),
        ..base
    }
}

/// The viewer's GI at start: the scene's and the flags' (`gi`), with temporal accumulation on
/// when `post.dynamic_gi` is and neither the scene nor a flag set `gi.temporal` (`set`).
/// Temporal accumulation is what lets one ray per pixel and frame ([`gi_at_scale`]) converge,
/// and a still camera refine; methods without it ignore the switch.
pub fn viewer_gi(gi: GiSettings, set: bool, settings: &DynamicResolution) -> GiSettings {
    GiSettings {
        temporal: gi.temporal || (settings.dynamic_gi && !set),
        ..gi
    }
}

/// `(w, h)` scaled by `steps` eighths, each axis rounded to the nearest pixel and at least 1.
pub fn scaled_size((w, h): (u32, u32), steps: u32) -> (u32, u32) {
    let scale = |v: u32| {
        ((u64::from(v) * u64::from(steps) + u64::from(STEPS) / 2) / u64::from(STEPS)).max(1) as u32
    };
    (scale(w), scale(h))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(budget_ms: f32) -> DynamicResolution {
        DynamicResolution {
            frame_budget_ms: budget_ms,
            min_scale: 0.125,
            refine_frames: 0,
            dynamic_gi: true,
            upscale: crate::scene::Upscale::Taa,
        }
    }

    /// Frames whose GPU time is `fixed_ms + per_full_ms · s²` at scale s (the model the
    /// controller assumes, plus a fixed cost it does not), measured two frames late as the
    /// viewer's frame loop reads them: the scales of the frames in flight.
    fn run(c: &mut ScaleController, fixed_ms: f64, per_full_ms: f64, frames: usize) -> Vec<u32> {
        let mut seen = Vec::new();
        let mut in_flight = std::collections::VecDeque::new();
        for _ in 0..frames {
            let measured = if in_flight.len() == 2 {
                in_flight.pop_front().map(|steps: u32| {
                    let s = f64::from(steps) / f64::from(STEPS);
                    (fixed_ms + per_full_ms * s * s, steps)
                })
            } else {
                None
            };
            let recorded = c.steps();
            c.observe(measured, false);
            in_flight.push_back(recorded);
            seen.push(c.steps());
        }
        seen
    }

    #[test]
    fn off_keeps_the_full_size() {
        let mut c = ScaleController::new(settings(0.0));
        assert_eq!(c.steps(), STEPS);
        assert_eq!(run(&mut c, 0.0, 1e4, 20), vec![STEPS; 20]);
        assert_eq!(c.internal_size((1280, 720)), (1280, 720));
    }

    #[test]
    fn an_over_budget_frame_jumps_down_to_the_scale_that_fits() {
        // 40 ms at full size against 16 ms: 40 s² ≤ 14.4 wants s ≤ 0.6, so 4/8.
        let mut c = ScaleController::new(settings(16.0));
        c.moving = STEPS;
        let seen = run(&mut c, 0.0, 40.0, 3);
        assert_eq!(*seen.last().expect("frames"), 4);
        // 1280×720 at 8900 ms on lavapipe, budget 100 ms: the floor, 1/8, where it starts.
        let mut c = ScaleController::new(settings(100.0));
        assert!(run(&mut c, 0.0, 8900.0, 20).iter().all(|&s| s == 1));
        assert_eq!(c.internal_size((1280, 720)), (160, 90));
    }

    #[test]
    fn a_device_that_holds_the_budget_reaches_the_full_size_in_a_few_jumps() {
        // A 4 ms full frame (1 ms fixed) against 16 ms: at 1/8, 1.05 ms predicts 67 ms at
        // the full size, over 0.7 · 16: the prediction's s² on the fixed cost makes it
        // cautious, so it goes up in a few jumps; then it stays.
        let mut gpu = ScaleController::new(settings(16.0));
        let seen = run(&mut gpu, 1.0, 3.0, 60);
        assert!(seen[30..].iter().all(|&s| s == STEPS), "{seen:?}");
        let changes = seen.windows(2).filter(|w| w[0] != w[1]).count();
        assert!(changes <= 4, "{changes} changes: {seen:?}");
    }

    #[test]
    fn the_scale_settles_under_budget_without_oscillating() {
        // 40 ms at full size, budget 16 ms, 2 ms of it fixed: s² ≤ (16 − 2)/38 wants s ≤ 0.607,
        // so 4/8 (11.5 ms); 5/8 would be 16.8 ms, over budget.
        let mut c = ScaleController::new(settings(16.0));
        c.moving = STEPS;
        let seen = run(&mut c, 2.0, 38.0, 200);
        let tail = &seen[100..];
        assert!(tail.iter().all(|&s| s == tail[0]), "{seen:?}");
        let s = f64::from(tail[0]) / 8.0;
        assert!(2.0 + 38.0 * s * s <= 16.0, "{seen:?}");
        assert_eq!(tail[0], 4, "{seen:?}");
        // Changes are few: down once or twice, then at most a step up.
        let changes = seen.windows(2).filter(|w| w[0] != w[1]).count();
        assert!(changes <= 3, "{changes} changes: {seen:?}");
    }

    #[test]
    fn a_frame_just_under_budget_does_not_step_up() {
        // At 6/8 a 0.6 budget frame: 7/8 predicts 0.6 · (7/6)² = 0.82 of the budget, over the
        // hysteresis's 0.7.
        let mut c = ScaleController::new(settings(100.0));
        c.moving = 6;
        for _ in 0..30 {
            assert_eq!(c.observe(Some((60.0, 6)), false), None);
        }
        assert_eq!(c.steps(), 6);
        // Frames of another scale (in flight at a change) do not count.
        for _ in 0..30 {
            assert_eq!(c.observe(Some((10.0, 8)), false), None);
        }
        // 0.45 of the budget: 7/8 predicts 0.61, up.
        for _ in 0..WINDOW {
            c.observe(Some((45.0, 6)), false);
        }
        assert_eq!(c.steps(), 7);
    }

    #[test]
    fn a_still_camera_refines_and_motion_returns_to_the_moving_scale() {
        let mut c = ScaleController::new(DynamicResolution {
            refine_frames: 5,
            ..settings(10.0)
        });
        // Moving: down to the floor.
        run(&mut c, 0.0, 1000.0, 10);
        assert_eq!(c.steps(), 1);
        for i in 0..4 {
            assert_eq!(c.observe(Some((1000.0, 1)), true), None, "still frame {i}");
        }
        assert_eq!(c.observe(Some((1000.0, 1)), true), Some(Change::Refine));
        assert_eq!(c.steps(), STEPS);
        // Full-size frames while still do not scale down.
        for _ in 0..20 {
            assert_eq!(c.observe(Some((1e5, 8)), true), None);
        }
        assert_eq!(c.observe(Some((1e5, 8)), false), Some(Change::Moving));
        assert_eq!(c.steps(), 1);
    }

    #[test]
    fn the_minimum_scale_is_a_floor_in_eighths() {
        let mut c = ScaleController::new(DynamicResolution {
            min_scale: 0.3,
            ..settings(1.0)
        });
        run(&mut c, 0.0, 1e4, 20);
        // 0.3 · 8 = 2.4, rounded up: 3/8.
        assert_eq!(c.steps(), 3);
        assert_eq!(
            c.set(DynamicResolution {
                min_scale: 0.5,
                ..settings(1.0)
            }),
            Some(Change::Settings)
        );
        assert_eq!(c.steps(), 4);
        assert_eq!(c.set(settings(0.0)), Some(Change::Settings));
        assert_eq!(c.steps(), STEPS);
    }

    #[test]
    fn scaled_sizes_round_and_stay_positive() {
        assert_eq!(scaled_size((1280, 720), 8), (1280, 720));
        assert_eq!(scaled_size((1280, 720), 3), (480, 270));
        assert_eq!(scaled_size((1, 3), 1), (1, 1));
        assert_eq!(scaled_size((333, 7), 5), (208, 4));
    }

    #[test]
    fn the_gi_traces_one_ray_below_the_full_size_and_the_scenes_count_at_it() {
        use crate::scene::GiMethod;
        let pt = GiSettings {
            method: GiMethod::Pathtrace,
            rays: 4,
            ..Default::default()
        };
        let on = settings(100.0);
        for steps in 1..STEPS {
            assert_eq!(gi_at_scale(pt, steps, &on).rays, 1, "{steps}/8");
        }
        assert_eq!(gi_at_scale(pt, STEPS, &on), pt);
        // Only the ray count changes: a scale change and its ray count are one new renderer.
        assert_eq!(gi_at_scale(pt, 1, &on), GiSettings { rays: 1, ..pt });
        // Off: the scene's count at every scale.
        let off = DynamicResolution {
            dynamic_gi: false,
            ..on
        };
        assert_eq!(gi_at_scale(pt, 1, &off), pt);
        // Methods that trace no rays per pixel keep their settings.
        for method in [GiMethod::None, GiMethod::Vpl] {
            let g = GiSettings {
                method,
                rays: 4,
                ..Default::default()
            };
            assert_eq!(gi_at_scale(g, 1, &on), g, "{method:?}");
        }
        // The hemisphere traces rays too.
        let h = GiSettings {
            method: GiMethod::Hemisphere,
            rays: 16,
            ..Default::default()
        };
        assert_eq!(gi_at_scale(h, 3, &on).rays, 1);
        // The controller applies its own scale: at the floor while moving, full when refined.
        let mut c = ScaleController::new(DynamicResolution {
            refine_frames: 2,
            ..on
        });
        assert_eq!(c.gi(pt).rays, 1);
        c.observe(None, true);
        assert_eq!(c.observe(None, true), Some(Change::Refine));
        assert_eq!(c.gi(pt), pt);
    }

    #[test]
    fn taa_upsampling_resolves_into_the_area_only_while_scaled() {
        use crate::scene::Upscale;
        let mut c = ScaleController::new(DynamicResolution {
            refine_frames: 1,
            ..settings(100.0)
        });
        let area = (969, 720);
        let internal = c.internal_size(area);
        assert_eq!(internal, (121, 90));
        assert_eq!(c.upsample_to(internal, area), Some(area));
        // Refined: the full-size frame, no upsampling (what `voxgi render` writes).
        assert_eq!(c.observe(None, true), Some(Change::Refine));
        assert_eq!(c.upsample_to(c.internal_size(area), area), None);
        // Bilinear, or dynamic resolution off: never.
        let mut b = ScaleController::new(DynamicResolution {
            upscale: Upscale::Bilinear,
            ..settings(100.0)
        });
        assert_eq!(b.upsample_to(b.internal_size(area), area), None);
        b.set(settings(0.0));
        assert_eq!(b.upsample_to(b.internal_size(area), area), None);
    }

    #[test]
    fn the_viewer_turns_temporal_gi_on_unless_the_scene_or_a_flag_set_it() {
        let on = settings(100.0);
        let off = GiSettings {
            temporal: false,
            ..Default::default()
        };
        assert!(viewer_gi(off, false, &on).temporal);
        // Set to off by the scene or a flag: stays off.
        assert!(!viewer_gi(off, true, &on).temporal);
        let set_on = GiSettings {
            temporal: true,
            ..off
        };
        assert!(viewer_gi(set_on, true, &on).temporal);
        let no_dynamic_gi = DynamicResolution {
            dynamic_gi: false,
            ..on
        };
        assert!(!viewer_gi(off, false, &no_dynamic_gi).temporal);
        // Nothing else changes.
        assert_eq!(
            viewer_gi(off, false, &on),
            GiSettings {
                temporal: true,
                ..off
            }
        );
    }
}
