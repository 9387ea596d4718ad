//! What the G-buffer's multiview pass and the stereo paths share: the suffix of the right
//! eye's pass names, and the drivers' known multiview defects with their version gate.

use crate::vk::vk;

/// Appended to the names of the right eye's passes in a one-frame stereo frame.
pub const RIGHT_EYE_SUFFIX: &str = "[R]";

/// A driver's known defect of Vulkan multiview that the multiview G-buffer works around.
///
/// **Mesa's draw module before 23.0.4** (lavapipe, `driverID` `MESA_LLVMPIPE`): `draw_vbo`
/// runs a multiview draw once per view (`u_foreach_bit` over the view mask, setting
/// `pt.user.viewid`). Triangles that need clipping go down the primitive pipeline, whose last
/// stage (`draw_pipe_vbuf.c`) batches them and tells the rasterizer their view
/// (`set_view_index`, which llvmpipe adds to the layer) only when it opens a batch
/// (`vbuf_first_tri` → `vbuf_start_prim`); a batch is closed only by a flush. Unclipped
/// triangles are emitted directly (`draw_pt_emit`), which flushes the open batch first and
/// sets the view each time. Nothing flushed when only the view changed, so when view 0's last
/// triangles went down the pipeline, view 1's clipped triangles joined view 0's open batch and
/// were rasterized with view index 0, into layer 0. Mesa commit bba644ce826 ("draw: fix
/// viewmask iterating", merge request 22628, April 2023) re-prepares the frontend when the
/// view changes (which flushes the batch); released in 23.0.4 and 23.1.0.
///
/// The workaround (`FLUSH_INSTANCE` in `gbuffer_vert.glsl`): every draw has two instances;
/// instance 0 puts all its vertices on one point inside the clip volume, so no triangle of it
/// is clipped, it is emitted directly, which flushes the previous view's batch, and it covers
/// no pixel; instance 1 is the mesh. The draw module runs the instances inside each view,
/// so every view's clipped triangles start a batch of their own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MultiviewDefect {
    /// Lavapipe of a Mesa without the fix; the version read from `driverInfo` (`None`: not
    /// readable, assumed affected since the workaround is exact either way).
    DrawViewBatch { mesa: Option<MesaVersion> },
}

/// A Mesa version from `driverInfo` (`Mesa 22.3.6 (LLVM 15.0.6)`); `prerelease` for
/// `-devel` and `-rcN` builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct MesaVersion {
    pub major: u32,
    pub minor: u32,
    pub patch: u32,
    pub prerelease: bool,
}

impl MesaVersion {
    /// The version in a `driverInfo` text starting `Mesa X.Y.Z`, `None` otherwise.
    pub fn parse(driver_info: &str) -> Option<Self> {
        let rest = driver_info.trim().strip_prefix("Mesa ")?;
        let end = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        let mut parts = rest[..end].split('.').map(str::parse::<u32>);
        let major = parts.next()?.ok()?;
        let minor = parts.next()?.ok()?;
        let patch = parts.next().unwrap_or(Ok(0)).ok()?;
        let suffix = &rest[end..];
        let prerelease = suffix.starts_with("-devel") || suffix.starts_with("-rc");
        Some(Self {
            major,
            minor,
            patch,
            prerelease,
        })
    }

    /// Whether this Mesa has the fix of [`MultiviewDefect::DrawViewBatch`]: 23.0.4 and
    /// later. Pre-releases of 23.0.4, 23.1.0 and 23.2.0 count as without it (the fix reached
    /// the main branch during 23.2.0-devel, after 23.1 had branched, and the 23.0 and 23.1
    /// branches took it later).
    pub fn has_draw_view_flush(self) -> bool {
        let v = (self.major, self.minor, self.patch);
        let late = [(23, 0, 4), (23, 1, 0), (23, 2, 0)];
        v >= (23, 0, 4) && !(self.prerelease && late.contains(&v))
    }

    /// `major.minor.patch`, with `-pre` for a pre-release.
    pub fn name(self) -> String {
        let pre = if self.prerelease { "-pre" } else { "" };
        format!("{}.{}.{}{pre}", self.major, self.minor, self.patch)
    }
}

impl MultiviewDefect {
    /// The defect of the driver `driver_id` whose `driverInfo` is `driver_info`, `None` for
    /// a driver not known to have one.
    pub fn of(driver_id: vk::DriverId, driver_info: &str) -> Option<Self> {
        if driver_id != vk::DriverId::MESA_LLVMPIPE {
            return None;
        }
        let mesa = MesaVersion::parse(driver_info);
        match mesa {
            Some(v) if v.has_draw_view_flush() => None,
            _ => Some(Self::DrawViewBatch { mesa }),
        }
    }

    /// One line for the command's output.
    pub fn describe(self) -> String {
        match self {
            Self::DrawViewBatch { mesa } => {
                let version = mesa.map_or_else(|| "of unknown version".into(), |v| v.name());
                format!(
                    "lavapipe (Mesa {version}) draws view 1's clipped triangles into layer 0 \
                     unless a flush separates the views (fixed in Mesa 23.0.4); every G-buffer \
                     draw carries a flushing instance"
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gate of the multiview workaround: lavapipe of a Mesa before the draw module's fix
    /// (23.0.4 on 23.0, 23.1.0 on), pre-releases of the two releases whose branch took the
    /// fix late, and an unreadable version; never another driver.
    #[test]
    fn multiview_defect_gate_follows_the_mesa_version() {
        let lvp = vk::DriverId::MESA_LLVMPIPE;
        let affected = |info: &str| MultiviewDefect::of(lvp, info).is_some();
        for info in [
            "Mesa 22.3.6 (LLVM 15.0.6)",
            "Mesa 21.1.0",
            "Mesa 23.0.3",
            "Mesa 23.0.0-rc5 (LLVM 15.0.7)",
            "Mesa 23.0.4-devel",
            "Mesa 23.1.0-rc2",
            "Mesa 23.2.0-devel (git-0123abcd)",
            "llvmpipe",
            "",
        ] {
            assert!(affected(info), "{info:?} has the defect");
        }
        for info in [
            "Mesa 23.0.4 (LLVM 15.0.7)",
            "Mesa 23.0.9",
            "Mesa 23.1.0",
            "Mesa 23.3.0-devel (git-0123abcd)",
            "Mesa 23.1.0-1ubuntu1 (LLVM 15.0.7)",
            "Mesa 24.2.8-1ubuntu1~24.04.1 (LLVM 19.1.1)",
            "Mesa 25.0.0",
        ] {
            assert!(!affected(info), "{info:?} has the fix");
        }
        let other = MultiviewDefect::of(vk::DriverId::MESA_RADV, "Mesa 22.3.6");
        assert_eq!(other, None);
        assert_eq!(
            MesaVersion::parse("Mesa 22.3.6 (LLVM 15.0.6)"),
            Some(MesaVersion {
                major: 22,
                minor: 3,
                patch: 6,
                prerelease: false
            })
        );
        let line = MultiviewDefect::of(lvp, "Mesa 22.3.6 (LLVM 15.0.6)")
            .map(MultiviewDefect::describe)
            .unwrap_or_default();
        assert!(
            line.contains("Mesa 22.3.6") && line.contains("23.0.4"),
            "{line}"
        );
    }
}
