//! `gi_temporal`: temporal accumulation of the voxel methods' indirect light (`gi.temporal`;
//! the shader's header has the method, after Schied et al. 2017 §4.1–4.2). It runs between a
//! method's passes and `gi_filter`: this frame's estimate and the reprojected history make
//! the accumulated light and its moments, which `gi_temporal_history` copies into the
//! history for the next frame and the filter reads to step back as the variance of the mean
//! falls.
//!
//! The history images are the graph's ([`RenderGraph::create_history_image`]): created once
//! per executor (a resize or a new graph starts them over) and shared by the frame slots.
//! Whether they hold a previous frame is a [`Cache`] with a fixed key, validated before each
//! recorded frame ([`GiTemporal::advance`]) and invalidated when the lights change
//! ([`GiTemporal::reset`]); a camera move keeps them (that is what reprojection is for).

use super::GiInputs;
use crate::graph::{Access, Cache, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use glam::{Mat4, Vec3};
use std::sync::{Arc, Mutex};

/// Push constants of `glsl/gi_temporal.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTemporalPush {
    /// The previous frame's un-jittered view-projection with its camera at the origin.
    pub prev_view_proj: [f32; 16],
    /// This frame's camera position minus the previous one; w 1 under orthographic projection.
    pub camera_move: [f32; 4],
    /// The previous frame's viewing direction.
    pub prev_forward: [f32; 4],
    pub max_frames: u32,
    pub has_history: u32,
    pub _pad: [u32; 2],
}

crate::push_constants!(GpuTemporalPush {
    prev_view_proj,
    camera_move,
    prev_forward,
    max_frames,
    has_history
});

/// What the reprojection needs of a frame's camera (one eye's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemporalView {
    /// The un-jittered view-projection with the camera at the origin.
    pub view_proj_relative: Mat4,
    pub position: Vec3,
    pub forward: Vec3,
    pub orthographic: bool,
}

/// Frames of history while objects move: the indirect light around a moving object changes
/// every frame, so the history must follow within a few frames (`tests/temporal.rs` measures
/// the trade on the Cornell mover).
pub const MOVING_FRAMES: u32 = 4;

/// One eye's history and the host state of its reprojection.
struct Eye {
    /// Whether the history holds a previous frame (fixed key; see the module docs).
    validity: Arc<Cache>,
    /// Shared with the pass's record closure, which reads the push constants.
    state: Arc<Mutex<EyeState>>,
}

#[derive(Default)]
struct EyeState {
    /// The camera of the frame to be recorded next ([`GiTemporal::set_views`]).
    next: Option<TemporalView>,
    /// The camera of the last recorded frame.
    prev: Option<TemporalView>,
    push: GpuTemporalPush,
}

impl Default for GpuTemporalPush {
    fn default() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

/// The temporal pass's pipeline and its per-eye state.
pub struct GiTemporal {
    pipeline: ComputePipeline,
    eyes: Vec<Eye>,
    max_frames: u32,
    /// Objects moved since the last recorded frame: its history is cut to [`MOVING_FRAMES`].
    moving: std::sync::atomic::AtomicBool,
}

impl GiTemporal {
    /// The accumulated light and its moments at `size` (what the history keeps, per eye).
    pub fn history_descs((w, h): (u32, u32)) -> Vec<ImageDesc> {
        ["gi temporal history", "gi temporal moments"]
            .iter()
            .map(|name| {
                ImageDesc::new_2d(name, vk::Format::R32G32B32A32_SFLOAT, w, h)
                    .with_usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST)
            })
            .collect()
    }

    /// `motion`: the G-buffer has motion vectors (scenes with moving objects), which
    /// [`GiInputs::motion`] then holds. `eyes`: histories kept, one per stereo eye.
    pub fn new(ctx: &Context, motion: bool, eyes: u32, max_frames: u32) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "gi_temporal.comp",
            PushLayout::of::<GpuTemporalPush>(),
            &crate::spec_constants![MOTION = motion],
        )?;
        let eyes = (0..eyes.max(1))
            .map(|e| Eye {
                validity: Cache::new(&format!("gi temporal history {e}")),
                state: Arc::new(Mutex::new(EyeState::default())),
            })
            .collect();
        Ok(Self {
            pipeline,
            eyes,
            max_frames: max_frames.max(1),
            moving: Default::default(),
        })
    }

    /// The cameras of the next frame to be recorded, one per eye (`Renderer::prepare`).
    pub fn set_views(&self, views: &[TemporalView]) {
        for (eye, view) in self.eyes.iter().zip(views) {
            lock(&eye.state).next = Some(*view);
        }
    }

    /// Objects moved: the next recorded frame keeps at most [`MOVING_FRAMES`] of history.
    pub fn objects_moved(&self) {
        self.moving.store(true, std::sync::atomic::Ordering::SeqCst);
    }

    /// Before recording a frame in slot `slot`: whether each eye has a history, and the
    /// reprojection from the last recorded frame's camera to this one's.
    pub fn advance(&self, slot: usize) {
        let moving = self.moving.swap(false, std::sync::atomic::Ordering::SeqCst);
        for eye in &self.eyes {
            // A fixed key: only a new image or `reset` makes the frame a first one.
            let first = eye.validity.validate(slot, 0);
            let mut s = lock(&eye.state);
            let Some(next) = s.next else { continue };
            let prev = s.prev.unwrap_or(next);
            s.push = GpuTemporalPush {
                prev_view_proj: prev.view_proj_relative.to_cols_array(),
                camera_move: (next.position - prev.position)
                    .extend(f32::from(u8::from(next.orthographic)))
                    .to_array(),
                prev_forward: prev.forward.extend(0.0).to_array(),
                max_frames: if moving {
                    self.max_frames.min(MOVING_FRAMES)
                } else {
                    self.max_frames
                },
                has_history: u32::from(!first && s.prev.is_some()),
                _pad: [0; 2],
            };
            s.prev = Some(next);
        }
    }

    /// The histories no longer apply (the lights changed): every pixel starts over.
    pub fn reset(&self) {
        for eye in &self.eyes {
            eye.validity.invalidate();
        }
    }

    /// Declares `gi_temporal` (this frame's `indirect` and eye `eye`'s history → the
    /// accumulated light and moments) and `gi_temporal_history` (→ the history); returns the
    /// accumulated light (a: history length) and the moments (x: mean squared luminance).
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
        indirect: ImageHandle,
        eye: u32,
    ) -> (ImageHandle, ImageHandle) {
        let c = Shader::Compute;
        let (w, h) = (i.width, i.height);
        let own = &self.eyes[(eye as usize).min(self.eyes.len() - 1)];
        let descs = Self::history_descs((w, h));
        let history: Vec<ImageHandle> = descs
            .iter()
            .map(|d| g.create_history_image(d.clone(), Access::Sampled(c), &own.validity))
            .collect();
        let out: Vec<ImageHandle> = descs
            .iter()
            .map(|d| {
                let name = format!("{} (this frame)", d.name);
                g.create_image(ImageDesc { name, ..d.clone() })
            })
            .collect();
        let pipe = *self.pipeline;
        let state = own.state.clone();
        g.add_pass("gi_temporal")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.normal, sampler, c)
            .bind_sampled(2, i.depth, sampler, c)
            .bind_sampled(3, indirect, sampler, c)
            .bind_sampled(4, history[0], sampler, c)
            .bind_sampled(5, history[1], sampler, c)
            .bind(6, out[0], Access::StorageWrite(c))
            .bind(7, out[1], Access::StorageWrite(c))
            // Without motion vectors the shader never reads binding 8; the depth fills it.
            .bind_sampled(8, i.motion.unwrap_or(i.depth), sampler, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                let push = lock(&state).push;
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        let extent = vk::Extent3D {
            width: w,
            height: h,
            depth: 1,
        };
        let mut pass = g.add_pass("gi_temporal_history");
        for k in 0..2 {
            pass = pass
                .read(out[k], Access::TransferRead)
                .write(history[k], Access::TransferWrite);
        }
        let copies = [(out[0], history[0]), (out[1], history[1])];
        pass.record(move |ctx| {
            for (from, to) in copies {
                ctx.cmd
                    .copy_image(ctx.image(from).raw, ctx.image(to).raw, extent);
            }
        });
        (out[0], out[1])
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_match_glsl() {
        crate::vk::check_push_against(&["gi_temporal.comp"], PushLayout::of::<GpuTemporalPush>())
            .unwrap();
    }
}
