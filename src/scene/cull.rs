//! Frustum culling of world-space boxes against a view-projection (camera or shadow view).

use super::Aabb;
use glam::{Mat4, Vec4};

/// False only when the box lies entirely outside one clip plane of `view_proj` (Vulkan clip
/// space: -w <= x, y <= w, 0 <= z <= w). Conservative: may keep boxes that are outside.
pub fn aabb_visible(view_proj: &Mat4, aabb: &Aabb) -> bool {
    if aabb.is_empty() {
        return false;
    }
    let corners: [Vec4; 8] = std::array::from_fn(|i| {
        let p = glam::Vec3::new(
            if i & 1 == 0 { aabb.min.x } else { aabb.max.x },
            if i & 2 == 0 { aabb.min.y } else { aabb.max.y },
            if i & 4 == 0 { aabb.min.z } else { aabb.max.z },
        );
        *view_proj * p.extend(1.0)
    });
    let outside = |f: &dyn Fn(&Vec4) -> bool| corners.iter().all(f);
    !(outside(&|c| c.x < -c.w)
        || outside(&|c| c.x > c.w)
        || outside(&|c| c.y < -c.w)
        || outside(&|c| c.y > c.w)
        || outside(&|c| c.z < 0.0)
        || outside(&|c| c.z > c.w))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn boxes_in_front_are_kept_behind_are_culled() {
        let view = glam::camera::rh::view::look_to_mat4(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
        let proj = glam::camera::rh::proj::directx::perspective(1.0, 1.0, 0.1, 100.0);
        let vp = proj * view;
        let front = Aabb {
            min: Vec3::new(-1.0, -1.0, -11.0),
            max: Vec3::new(1.0, 1.0, -9.0),
        };
        let behind = Aabb {
            min: Vec3::new(-1.0, -1.0, 9.0),
            max: Vec3::new(1.0, 1.0, 11.0),
        };
        let beside = Aabb {
            min: Vec3::new(50.0, -1.0, -11.0),
            max: Vec3::new(52.0, 1.0, -9.0),
        };
        let around = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        assert!(aabb_visible(&vp, &front));
        assert!(!aabb_visible(&vp, &behind));
        assert!(!aabb_visible(&vp, &beside));
        assert!(
            aabb_visible(&vp, &around),
            "a box containing the camera is kept"
        );
    }
}
