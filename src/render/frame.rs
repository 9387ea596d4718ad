//! The frame constants: lights, shadow views and camera computed by [`Renderer::prepare`],
//! written per frame slot (with TAA jitter and motion) by [`Renderer::write_frame`].

use super::*;

impl Renderer {
    /// Computes frame constants, shadow views and culled draw lists for the scene's camera and
    /// lights and `settings`. Call again after changing them (the viewer does, every frame);
    /// a new size, shadow resolution, cascade count or tone map also needs a new graph.
    /// Dynamic objects are drawn, and re-voxelized by [`Self::write_frame`], at their
    /// transform in `scene` (the viewer's editor moves them).
    ///
    /// A one-frame stereo renderer takes `scene.camera` as the centre between its eyes.
    pub fn prepare(&mut self, scene: &Scene) -> Result<(), RenderError> {
        check_projection(&scene.camera, &self.settings, self.stereo.is_some())?;
        let s = self.settings.clone();
        if let Some(v) = &mut self.voxels {
            v.follow_objects(scene);
        }
        if let Some((gi, _)) = &mut self.gi {
            gi.follow_objects(scene);
        }
        if let Some(pass) = &mut self.voxel_debug {
            pass.follow_objects(scene);
        }
        let eyes = self.stereo.as_ref().map(|st| {
            let eye = |e| scene.camera.eye(st.rig, e);
            (eye(crate::scene::Eye::Left), eye(crate::scene::Eye::Right))
        });
        // The camera of `frame_data`: the left eye's in a stereo frame.
        let camera = eyes.map_or(scene.camera, |(left, _)| left);
        let (mut views, per_light) = shadow_views(scene, s.time_s, &s.shadow);
        let lights = frame_lights(&scene.lights, &s.shadow);
        let aspect = s.width as f32 / s.height as f32;
        // The directional lights' cascades follow every light's own views (the light maps
        // draw only those): GpuLight::info.w = first cascade view | cascade count << 16.
        let base_views = views.len();
        let mut cascades_of = vec![0u32; lights.len()];
        let cascade_sets = crate::light::cascade::cascade_views(
            &lights,
            &camera,
            aspect,
            &scene.aabb_at(s.time_s),
            &s.shadow,
            |li| views[per_light[li].first as usize].texel_footprint,
        );
        for (li, set) in cascade_sets {
            cascades_of[li] = views.len() as u32 | (set.len() as u32) << 16;
            views.extend(set);
        }
        // The graph's shadow array holds every cascade the settings allow, so that a camera
        // whose far cascades are dropped (no finer than the whole-scene map) and later come
        // back needs no new graph.
        let capacity = match s.shadow.cascades {
            n if n >= 2 => n as usize * lights.iter().filter(|l| l.is_directional()).count(),
            _ => 0,
        };
        if base_views + capacity > MAX_SHADOW_VIEWS {
            return Err(RenderError::TooManyShadowViews(base_views + capacity));
        }
        let view_proj = camera.view_proj(aspect);
        let mut f = GpuFrame::zeroed();
        set_frame_camera(&mut f, &camera, aspect);
        f.environment = crate::scene::Environment::frame_constants(scene.environment.as_ref());
        f.radiance_scale = self.pre_exposure.frame_constants();
        f.counts = [lights.len() as u32, views.len() as u32, s.width, s.height];
        f.shadow = [
            s.shadow.bias_texels,
            s.shadow.slope_bias_texels,
            s.shadow.normal_offset_texels,
            s.shadow.pcf_radius as f32,
        ];
        for (i, light) in lights.iter().enumerate() {
            f.lights[i] = gpu_light(light, per_light[i].first, per_light[i].count);
            f.lights[i].info[3] = cascades_of[i];
        }
        for (i, v) in views.iter().enumerate() {
            f.shadow_views[i] = GpuShadowView {
                view_proj: v.view_proj.to_cols_array(),
                params: [v.texel_footprint, v.projection.gpu_code(), v.near, v.far],
                axis: v.axis.extend(v.split_far_m).to_array(),
            };
        }
        // The right eye: the same constants seen from its camera.
        let mut right_changed = false;
        let mut view_projs = vec![view_proj];
        if let (Some(st), Some((_, right))) = (&mut self.stereo, eyes) {
            let mut fr = f;
            set_frame_camera(&mut fr, &right, aspect);
            right_changed = bytemuck::bytes_of(&fr) != bytemuck::bytes_of(&st.frame_right);
            st.frame_right = fr;
            view_projs.push(right.view_proj(aspect));
        }
        if let Some(pass) = &mut self.direct_emitters {
            pass.update_scene(scene, s.time_s);
        }
        // Accumulated indirect light is valid only while camera, lights and settings stay;
        // with reprojection (temporal accumulation) a camera move keeps it.
        if let Some((gi, _)) = &mut self.gi {
            gi.update_scene(scene, s.time_s);
            let changed =
                right_changed || bytemuck::bytes_of(&f) != bytemuck::bytes_of(&self.frame_data);
            let lights_changed = light_key(&f) != light_key(&self.frame_data);
            if lights_changed {
                gi.lights_changed();
            } else if changed && !gi.reprojects() {
                gi.reset();
            }
            let mut cameras = vec![temporal_view(&camera, aspect)];
            if let Some((_, right)) = eyes {
                cameras.push(temporal_view(&right, aspect));
            }
            gi.set_views(&cameras);
        }
        self.frame_data = f;
        self.shadow_view_count = base_views as u32;
        self.cascade_view_capacity = capacity as u32;
        let (own, cascades) = views.split_at(base_views);
        self.scene
            .update_draws(scene, s.time_s, &view_projs, (own, cascades));
        Ok(())
    }

    /// Writes the frame constants of frame slot `slot` (call after the slot's fence), and the
    /// dynamic objects' voxels at `settings.time_s`.
    pub fn write_frame(&mut self, slot: usize) {
        let mut attributes_moved = false;
        if let Some(v) = &mut self.voxels {
            if let Err(e) = v.update(self.settings.time_s, slot) {
                log::warn!("dynamic objects not re-voxelized: {e}");
            }
            attributes_moved = v.attributes_moved();
        }
        if let Some((gi, _)) = &mut self.gi {
            gi.update_dynamic(self.settings.time_s, slot);
            if attributes_moved {
                gi.objects_moved();
            }
            gi.advance(slot);
        }
        if let Some(pass) = &mut self.voxel_debug {
            pass.update(self.settings.time_s, slot);
        }
        if let Some(pass) = &mut self.direct_emitters {
            pass.write_slot(slot);
        }
        self.validate_caches(slot);
        // With TAA every frame renders with its own sub-pixel jitter; `frame_data` keeps the
        // un-jittered camera (what `prepare` compares to restart accumulation).
        let view_proj = glam::Mat4::from_cols_array(&self.frame_data.view_proj);
        let mut frame = jittered(self.frame_data, &mut self.post);
        let motion = self.scene.motion;
        if motion {
            // The previous frame written is the motion vectors' "before", camera and models.
            let prev = self.prev_view_proj.unwrap_or(view_proj);
            frame.prev_view_proj = prev.to_cols_array();
            self.prev_view_proj = Some(view_proj);
            self.scene.advance_motion();
        }
        self.scene.write_frame(slot, &frame);
        if let Some(st) = &mut self.stereo {
            // The right eye's own TAA history and jitter sequence.
            let right = st.jittered_right_frame(motion);
            self.scene.write_frame_right(slot, &right);
        }
    }

    /// Opens the cached light-space passes of slot `slot` where their inputs changed since
    /// they were last rendered (`graph::Cache`; nothing while `shadow.cache` is off).
    fn validate_caches(&self, slot: usize) {
        let Ok(draws) = self.scene.draws.read() else {
            return;
        };
        let layers = self.shadow_view_count + self.cascade_view_capacity;
        self.shadow_depth
            .validate(slot, &self.frame_data, &draws, layers);
        if let Some((_, Some(light_map))) = &self.gi {
            light_map.validate(slot, &self.frame_data, &draws);
        }
    }
}

fn gpu_light(light: &Light, first_view: u32, views: u32) -> GpuLight {
    let v4 = |v: Vec3| [v.x, v.y, v.z, 0.0];
    match *light {
        Light::Point {
            position,
            intensity_w_sr,
        } => GpuLight {
            position: v4(position),
            intensity: v4(intensity_w_sr),
            info: [LIGHT_POINT, first_view, views, 0],
            ..Default::default()
        },
        Light::Spot {
            position,
            direction,
            intensity_w_sr,
            cutoff_deg,
            beam_deg,
        } => GpuLight {
            position: v4(position),
            direction: v4(direction),
            intensity: v4(intensity_w_sr),
            spot: [
                cutoff_deg.to_radians().cos(),
                cutoff_deg.to_radians(),
                beam_deg.to_radians(),
                0.0,
            ],
            info: [LIGHT_SPOT, first_view, views, 0],
        },
        Light::Directional {
            direction,
            irradiance_w_m2,
        } => GpuLight {
            direction: v4(direction),
            intensity: v4(irradiance_w_m2),
            info: [LIGHT_DIRECTIONAL, first_view, views, 0],
            ..Default::default()
        },
        Light::Element {
            position,
            normal,
            intensity_w_sr,
            pcss_size_m,
        } => GpuLight {
            position: v4(position),
            direction: v4(normal),
            intensity: v4(intensity_w_sr),
            spot: [0.0, 0.0, 0.0, pcss_size_m],
            info: [LIGHT_ELEMENT, first_view, views, 0],
        },
        // A whole sphere (`--area-shadows pcss`): seen from any direction it is a disk of
        // area πR² and radiance L, so a point light of intensity I = L·πR² at its centre gives
        // exactly its irradiance E = π L (R/d)² cos θ wherever it is wholly above the
        // receiver's horizon; spot.w, its diameter, asks for PCSS (glsl/include/shadow.glsl).
        Light::Sphere {
            position,
            radius_m,
            radiance_w_sr_m2,
            ..
        } => GpuLight {
            position: v4(position),
            intensity: v4(radiance_w_sr_m2 * (std::f32::consts::PI * radius_m * radius_m)),
            spot: [0.0, 0.0, 0.0, 2.0 * radius_m],
            info: [LIGHT_POINT, first_view, views, 0],
            ..Default::default()
        },
        Light::Rectangle { .. } => {
            unreachable!("prepare renders rectangles as elements (frame_lights)")
        }
    }
}

/// With TAA every frame renders with its own sub-pixel jitter: `frame` (un-jittered, what
/// `prepare` compares to restart accumulation) moved by `post`'s next jitter.
pub(super) fn jittered(mut frame: GpuFrame, post: &mut crate::post::PostPasses) -> GpuFrame {
    if post.jitters() {
        let view_proj = glam::Mat4::from_cols_array(&frame.view_proj);
        let jitter_ndc = post.begin_frame(view_proj);
        let jitter = crate::post::taa::jitter_matrix(jitter_ndc);
        // The inverse stays camera-relative (see `camera_relative_inverse`).
        let inv_relative = glam::Mat4::from_cols_array(&frame.inv_view_proj);
        frame.view_proj = (jitter * view_proj).to_cols_array();
        frame.inv_view_proj = (inv_relative * jitter.inverse()).to_cols_array();
        frame.jitter_ndc = [jitter_ndc.x, jitter_ndc.y, 0.0, 0.0];
    }
    frame
}

/// Sets the frame constants that depend on the camera: view-projection, its camera-relative
/// inverse, the camera position and its viewing direction with the projection.
/// What of the frame constants the indirect light depends on besides the camera: the lights
/// (without their cascade views, which follow the camera), the environment, the
/// pre-exposure and the shadow parameters. A change of it starts temporal accumulation over.
fn light_key(f: &GpuFrame) -> u64 {
    let mut key = crate::graph::KeyHasher::default();
    for l in &f.lights[..(f.counts[0] as usize).min(f.lights.len())] {
        let info = [l.info[0], l.info[1], l.info[2]];
        key.bytes(bytemuck::bytes_of(&[
            l.position,
            l.direction,
            l.intensity,
            l.spot,
        ]))
        .bytes(bytemuck::bytes_of(&info));
    }
    key.u64(u64::from(f.counts[0]))
        .bytes(bytemuck::bytes_of(&[
            f.environment,
            f.radiance_scale,
            f.shadow,
        ]))
        .finish()
}

/// The camera as the temporal accumulation reprojects with it (un-jittered).
fn temporal_view(camera: &crate::scene::Camera, aspect: f32) -> crate::gi::TemporalView {
    let mut relative = *camera;
    relative.position = glam::Vec3::ZERO;
    crate::gi::TemporalView {
        view_proj_relative: relative.view_proj(aspect),
        position: camera.position,
        forward: camera.forward,
        orthographic: camera.is_orthographic(),
    }
}

fn set_frame_camera(f: &mut GpuFrame, camera: &crate::scene::Camera, aspect: f32) {
    f.view_proj = camera.view_proj(aspect).to_cols_array();
    f.inv_view_proj = camera_relative_inverse(camera, aspect).to_cols_array();
    f.camera_position = camera.position.extend(1.0).to_array();
    let ortho_height_m = if camera.is_orthographic() {
        camera.ortho_height_m
    } else {
        0.0
    };
    f.camera_forward = camera.forward.extend(ortho_height_m).to_array();
}

/// The inverse of the camera's view-projection with the camera moved to the origin:
/// `pixel_world_position` (glsl/include/frame.glsl) unprojects a pixel relative to the camera
/// with it and adds the camera's position, so that a scene far from the world origin keeps
/// f32 precision.
fn camera_relative_inverse(camera: &crate::scene::Camera, aspect: f32) -> glam::Mat4 {
    let mut relative = *camera;
    relative.position = glam::Vec3::ZERO;
    relative.view_proj(aspect).inverse()
}
