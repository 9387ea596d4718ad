//! Human-readable dumps of a compiled graph: text and Graphviz dot.

use super::compile::CompiledGraph;
use super::RenderGraph;
use std::fmt::Write as _;

impl CompiledGraph {
    /// Passes (with their barriers), culled passes, resources with lifetimes and placements,
    /// and transient memory with and without aliasing.
    pub fn dump_text(&self, graph: &RenderGraph) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "passes ({} live, {} culled):",
            self.order.len(),
            self.culled.len()
        );
        for (pos, &p) in self.order.iter().enumerate() {
            let _ = writeln!(
                s,
                "  [{pos}] {}{}",
                self.pass_names[p],
                conditional_note(graph, p)
            );
            for (id, access, _, _) in &graph.passes[p].accesses {
                let _ = writeln!(
                    s,
                    "        {:?} {}",
                    access, self.resource_names[id.0 as usize]
                );
            }
            for b in &self.pass_barriers[pos] {
                let _ = writeln!(
                    s,
                    "        barrier {} mips {}..{} layers {}..{}: {:?}/{:?} -> {:?}/{:?}, {:?} -> {:?}",
                    self.resource_names[b.resource.0 as usize],
                    b.sub.base_mip,
                    b.sub.base_mip + b.sub.mip_count,
                    b.sub.base_layer,
                    b.sub.base_layer + b.sub.layer_count,
                    b.src_stages,
                    b.src_access,
                    b.dst_stages,
                    b.dst_access,
                    b.old_layout,
                    b.new_layout
                );
            }
        }
        for &p in &self.culled {
            let _ = writeln!(s, "  culled: {}", self.pass_names[p]);
        }
        if !self.final_barriers.is_empty() {
            let _ = writeln!(s, "  end of frame:");
            for b in &self.final_barriers {
                let _ = writeln!(
                    s,
                    "        barrier {}: {:?} -> {:?}, {:?} -> {:?}",
                    self.resource_names[b.resource.0 as usize],
                    b.src_stages,
                    b.dst_stages,
                    b.old_layout,
                    b.new_layout
                );
            }
        }
        let _ = writeln!(s, "resources:");
        for (i, name) in self.resource_names.iter().enumerate() {
            let kind = if graph.resources[i].is_transient() {
                "transient"
            } else {
                "imported"
            };
            let life = match self.lifetimes[i] {
                Some((a, b)) => format!("passes {a}..={b}"),
                None => "unused".into(),
            };
            let place = match self.placements[i] {
                Some(p) => format!(
                    ", arena {} @ {} ({} bytes)",
                    p.arena, p.offset, p.size_bytes
                ),
                None => String::new(),
            };
            let _ = writeln!(s, "  {name} ({kind}): {life}{place}");
        }
        let _ = writeln!(
            s,
            "transient memory ({} transients, {} arenas): {}",
            self.memory.transient_count,
            self.arenas.len(),
            self.memory.summary()
        );
        for (i, a) in self.arenas.iter().enumerate() {
            let _ = writeln!(
                s,
                "  arena {i}: memory type {}, {}, {} bytes",
                a.memory_type,
                if a.holds_buffers { "buffers" } else { "images" },
                a.size_bytes
            );
        }
        s
    }

    /// Graphviz dot: passes as boxes, resources as ellipses, edges for reads and writes;
    /// culled passes dashed, conditional ones (`.when()`) dotted.
    pub fn dump_dot(&self, graph: &RenderGraph) -> String {
        let mut s = String::from("digraph voxgi {\n  rankdir=LR;\n");
        for (i, name) in self.resource_names.iter().enumerate() {
            let style = if graph.resources[i].is_transient() {
                ""
            } else {
                ", style=bold"
            };
            let _ = writeln!(s, "  r{i} [label=\"{name}\", shape=ellipse{style}];");
        }
        for (p, pass) in graph.passes.iter().enumerate() {
            let culled = self.culled.contains(&p);
            let style = match (culled, pass.condition.is_some()) {
                (true, _) => ", style=dashed",
                (false, true) => ", style=dotted",
                (false, false) => "",
            };
            let _ = writeln!(
                s,
                "  p{p} [label=\"{}{}\", shape=box{style}];",
                pass.name,
                conditional_note(graph, p)
            );
            for (id, access, _, _) in &pass.accesses {
                let info = access.info();
                if info.reads {
                    let _ = writeln!(s, "  r{} -> p{p} [label=\"{:?}\"];", id.0, access);
                }
                if info.writes {
                    let _ = writeln!(s, "  p{p} -> r{} [label=\"{:?}\"];", id.0, access);
                }
            }
        }
        s.push_str("}\n");
        s
    }
}

/// Marks a pass declared with `.when()`: it records only in the frame slots its condition
/// leaves open (its barriers and timestamps are emitted in every frame); a pass declared with
/// `.cached()` records only in frames where its cache's key changed.
fn conditional_note(graph: &RenderGraph, pass: usize) -> &'static str {
    let p = &graph.passes[pass];
    match (&p.cache, &p.condition) {
        (Some(_), _) => " (cached)",
        (None, Some(_)) => " (conditional)",
        (None, None) => "",
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::compile::EstimateOracle;
    use crate::graph::{Access, RenderGraph, Shader};
    use crate::vk::{vk, ImageDesc};

    #[test]
    fn dumps_name_every_pass_and_resource() {
        let mut g = RenderGraph::new();
        let a = g.create_image(ImageDesc::new_2d("color", vk::Format::R8G8B8A8_UNORM, 8, 8));
        let out = g.import_buffer_desc("readback", 256, Access::HostRead);
        g.add_pass("draw")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("copy")
            .when(Some(Default::default()))
            .read(a, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let cache = crate::graph::Cache::new("baked");
        let baked = g.create_cached_image(
            ImageDesc::new_2d("baked", vk::Format::R8G8B8A8_UNORM, 8, 8),
            Access::Sampled(Shader::Compute),
            std::slice::from_ref(&cache),
        );
        g.add_pass("bake")
            .cached(Some(&cache))
            .write(baked, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("use_baked")
            .read(baked, Access::Sampled(Shader::Compute))
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let c = g.compile(&EstimateOracle).expect("compiles");
        let text = c.dump_text(&g);
        for word in [
            "draw",
            "copy",
            "color",
            "readback",
            "barrier",
            "transient memory",
        ] {
            assert!(text.contains(word), "text dump lacks {word}:\n{text}");
        }
        assert!(text.contains("] copy (conditional)"), "{text}");
        assert!(text.contains("] bake (cached)"), "{text}");
        assert!(!text.contains("draw (conditional)"), "{text}");
        let dot = c.dump_dot(&g);
        assert!(
            dot.contains("copy (conditional)\", shape=box, style=dotted"),
            "{dot}"
        );
        assert!(dot.starts_with("digraph") && dot.contains("p0 -> r0") && dot.contains("r0 -> p1"));
    }
}
