//! Cached resources: persistent images the graph owns, kept from frame to frame while what
//! they were computed from is unchanged (Oetke 2017's shadow pass keeps a shadow map until its
//! light or the geometry in its view moves).
//!
//! A [`Cache`] is a validity: the key of the change set its images were last rendered from
//! (light parameters, the shadow views, the draws in those views). The passes that produce
//! its images declare it with [`super::PassBuilder::cached`], which is `.when()` with the
//! cache's [`SlotCondition`]: the host calls [`Cache::validate`] with the frame's key before
//! recording a slot, which opens the slot only when the key differs from the one the images
//! hold. The images are created with [`super::RenderGraph::create_cached_image`]: the
//! executor allocates them once (outside the per-slot arenas) and shares them between every
//! frame slot, so one render serves all slots; a new executor (new images) invalidates the
//! cache. The record closures never decide whether to run.

use super::SlotCondition;
use std::sync::{Arc, Mutex};

/// What a cache holds (see the module docs).
#[derive(Debug, Default)]
struct Held {
    /// The key the images were last rendered from (`None`: never, or invalidated).
    key: Option<u64>,
    /// Frames validated with the condition open since the cache was made.
    renders: u64,
    /// Frames validated with the condition closed.
    reuses: u64,
}

/// The validity of a set of cached images, shared by the passes that produce them.
#[derive(Debug)]
pub struct Cache {
    name: String,
    condition: Arc<SlotCondition>,
    held: Mutex<Held>,
}

impl Cache {
    /// A cache that holds nothing yet (its first frame renders).
    pub fn new(name: &str) -> Arc<Self> {
        Arc::new(Self {
            name: name.to_owned(),
            condition: Arc::new(SlotCondition::default()),
            held: Mutex::new(Held::default()),
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The condition of the passes that produce the cache's images.
    pub fn condition(&self) -> Arc<SlotCondition> {
        self.condition.clone()
    }

    /// Before recording frame slot `slot`, whose inputs have `key`: opens the slot's
    /// condition when the images hold another key (or none), closes it otherwise, and takes
    /// `key` as held. The images are shared by every slot and the queue runs frames in
    /// order, so the frame that renders them serves every later frame of either slot.
    /// Returns whether the slot renders. Call it once per recorded frame, right before
    /// recording it (a validated frame that is not recorded would leave the key claimed).
    pub fn validate(&self, slot: usize, key: u64) -> bool {
        let Ok(mut held) = self.held.lock() else {
            // A poisoned lock: trust nothing, render.
            self.condition.set(slot, true);
            return true;
        };
        let render = held.key != Some(key);
        held.key = Some(key);
        if render {
            held.renders += 1;
        } else {
            held.reuses += 1;
        }
        self.condition.set(slot, render);
        render
    }

    /// Forgets the held key: the next [`Self::validate`] renders (new images, or a change
    /// the key does not cover).
    pub fn invalidate(&self) {
        if let Ok(mut held) = self.held.lock() {
            held.key = None;
        }
    }

    /// Frames that rendered the images and frames that reused them, since the cache was made.
    pub fn counts(&self) -> (u64, u64) {
        self.held
            .lock()
            .map(|h| (h.renders, h.reuses))
            .unwrap_or_default()
    }
}

/// Hashes the bytes of a change set into a cache key (FNV-1a, 64 bits: the key only has to
/// tell two frames' inputs apart, and collisions among a handful of recent keys are
/// negligible at 2⁻⁶⁴).
#[derive(Clone, Copy, Debug)]
pub struct KeyHasher(u64);

impl Default for KeyHasher {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl KeyHasher {
    pub fn bytes(&mut self, bytes: &[u8]) -> &mut Self {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self
    }

    pub fn u64(&mut self, v: u64) -> &mut Self {
        self.bytes(&v.to_le_bytes())
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first frame renders; the same key reuses in every slot; a new key renders once,
    /// then reuses; invalidation renders again.
    #[test]
    fn validate_opens_only_when_the_key_changes() {
        let c = Cache::new("test");
        let cond = c.condition();
        assert!(c.validate(0, 7) && cond.is_open(0));
        assert!(!c.validate(1, 7) && !cond.is_open(1));
        assert!(!c.validate(0, 7) && !cond.is_open(0));
        assert!(c.validate(1, 8) && cond.is_open(1));
        assert!(!c.validate(0, 8) && !cond.is_open(0));
        c.invalidate();
        assert!(c.validate(1, 8));
        assert_eq!(c.counts(), (3, 3));
    }

    /// A cached image is no output of its own: its producer lives while a pass reads it and
    /// is culled with it otherwise (a debug view that reads no shadow map renders none).
    #[test]
    fn cached_images_live_only_while_read() {
        use crate::graph::compile::EstimateOracle;
        use crate::graph::{Access, RenderGraph, Shader};
        use crate::vk::{vk, ImageDesc};
        let build = |read: bool| {
            let mut g = RenderGraph::new();
            let cache = Cache::new("maps");
            let desc = ImageDesc::new_2d("maps", vk::Format::R8G8B8A8_UNORM, 8, 8);
            let maps = g.create_cached_image(
                desc,
                Access::Sampled(Shader::Compute),
                std::slice::from_ref(&cache),
            );
            let out = g.import_buffer_desc("out", 256, Access::HostRead);
            g.add_pass("bake")
                .cached(Some(&cache))
                .write(maps, Access::StorageWrite(Shader::Compute))
                .record(|_| {});
            let pass = g.add_pass("copy").write(out, Access::TransferWrite);
            let pass = if read {
                pass.read(maps, Access::TransferRead)
            } else {
                pass
            };
            pass.record(|_| {});
            let c = g.compile(&EstimateOracle).expect("compiles");
            c.order
                .iter()
                .map(|&p| c.pass_names[p].clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(build(true), ["bake", "copy"]);
        assert_eq!(build(false), ["copy"]);
    }

    /// A history is written after the pass that reads it: its writer lives while that reader
    /// lives (walking back from the output alone would cull it), and both go when nothing
    /// reads the reader's output.
    #[test]
    fn a_history_lives_with_its_reader() {
        use crate::graph::compile::EstimateOracle;
        use crate::graph::{Access, RenderGraph, Shader};
        use crate::vk::{vk, ImageDesc};
        let build = |read: bool| {
            let mut g = RenderGraph::new();
            let validity = Cache::new("history");
            let desc = ImageDesc::new_2d("h", vk::Format::R32G32B32A32_SFLOAT, 8, 8);
            let history =
                g.create_history_image(desc.clone(), Access::Sampled(Shader::Compute), &validity);
            let now = g.create_image(desc);
            let out = g.import_buffer_desc("out", 256, Access::HostRead);
            g.add_pass("accumulate")
                .read(history, Access::Sampled(Shader::Compute))
                .write(now, Access::StorageWrite(Shader::Compute))
                .record(|_| {});
            let pass = g.add_pass("use").write(out, Access::TransferWrite);
            let pass = if read {
                pass.read(now, Access::TransferRead)
            } else {
                pass
            };
            pass.record(|_| {});
            g.add_pass("keep")
                .read(now, Access::TransferRead)
                .write(history, Access::TransferWrite)
                .record(|_| {});
            let c = g.compile(&EstimateOracle).expect("compiles");
            c.order
                .iter()
                .map(|&p| c.pass_names[p].clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(build(true), ["accumulate", "use", "keep"]);
        assert_eq!(build(false), ["use"]);
    }

    #[test]
    fn keys_tell_inputs_apart() {
        let k = |b: &[u8]| KeyHasher::default().bytes(b).finish();
        assert_ne!(k(&[1, 2]), k(&[2, 1]));
        assert_eq!(k(&[1, 2]), k(&[1, 2]));
        assert_ne!(k(&[]), k(&[0]));
    }
}
