//! A window surface and its swapchain: acquire, present, recreate on resize.
//!
//! Swapchain images are wrapped as [`Image`]s (with views, without memory) so the render graph
//! can import them with [`Access::Present`](crate::graph::Access::Present) and derive every
//! transition; this module records no commands.

use super::release::{Garbage, ReleaseQueue};
use super::{Context, Image, ImageDesc, VkError};
use ash::khr;
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};
use std::ffi::CStr;
use std::sync::Arc;

/// Instance extensions a surface on `display` needs (pass them in
/// [`ContextDesc::instance_extensions`](super::ContextDesc)).
pub fn surface_extensions(display: RawDisplayHandle) -> Result<Vec<&'static CStr>, VkError> {
    let names = ash_window::enumerate_required_extensions(display).map_err(VkError::vk(
        "list the surface extensions of this window system",
    ))?;
    Ok(names
        .iter()
        // SAFETY: ash-window returns pointers to static NUL-terminated extension names.
        .map(|&p| unsafe { CStr::from_ptr(p) })
        .collect())
}

/// What [`Swapchain::acquire`] got.
pub enum Acquired {
    /// Render into `images[index]`; wait for `ready` before writing it.
    Image { index: u32, ready: vk::Semaphore },
    /// The surface changed (resize); recreate and try the next frame.
    OutOfDate,
    /// The surface is gone: another client destroyed its window, and the windowing system
    /// says so before winit reports `Destroyed`. Nothing more can be drawn.
    SurfaceLost,
}

/// What [`Swapchain::present`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    /// Presented; the swapchain still matches the surface.
    Done,
    /// Presented or not, the swapchain should be recreated (resized, suboptimal).
    Recreate,
    /// The surface is gone (as [`Acquired::SurfaceLost`], found at presentation).
    SurfaceLost,
}

/// Dropping it waits for the device and destroys the swapchain and then the surface: drop it
/// before the window (declare it before the window in the owning struct).
pub struct Swapchain {
    release: Arc<ReleaseQueue>,
    surface_loader: khr::surface::Instance,
    loader: khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    raw: vk::SwapchainKHR,
    /// The swapchain images, viewed as `format`. The [`Image`]s own only their views.
    pub images: Vec<Image>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    /// Signalled by acquire, one per frame slot (reused once the slot's fence signalled).
    acquire_semaphores: Vec<vk::Semaphore>,
    /// Signalled by the frame's submission, waited for by present; one per image, because a
    /// presentation may still hold it when another image is acquired.
    render_semaphores: Vec<vk::Semaphore>,
}

/// Formats in order of preference. UNORM only: the renderer writes sRGB-encoded values, which
/// must reach the display unchanged (an `_SRGB` format would encode them twice).
const FORMATS: &[vk::Format] = &[vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];

impl Swapchain {
    /// A surface for the window and a swapchain of `extent` (clamped to what the surface
    /// allows). `slots` is the number of frames in flight.
    pub fn new(
        ctx: &Context,
        display: RawDisplayHandle,
        window: RawWindowHandle,
        extent: vk::Extent2D,
        slots: usize,
    ) -> Result<Self, VkError> {
        let surface_loader = khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        // SAFETY: the handles come from a live window that outlives the swapchain (the caller
        // drops the swapchain before the window).
        let surface =
            unsafe { ash_window::create_surface(&ctx.entry, &ctx.instance, display, window, None) }
                .map_err(VkError::vk("create a window surface"))?;
        let mut s = Self {
            release: Arc::clone(&ctx.release),
            surface_loader,
            loader: khr::swapchain::Device::new(&ctx.instance, &ctx.device),
            surface,
            raw: vk::SwapchainKHR::null(),
            images: Vec::new(),
            format: vk::Format::UNDEFINED,
            extent,
            acquire_semaphores: Vec::new(),
            render_semaphores: Vec::new(),
        };
        let result = s.check_support(ctx).and_then(|()| {
            for _ in 0..slots.max(1) {
                let sem = s.semaphore(ctx)?;
                s.acquire_semaphores.push(sem);
            }
            s.recreate(ctx, extent)
        });
        result.map(|()| s)
    }

    fn semaphore(&self, ctx: &Context) -> Result<vk::Semaphore, VkError> {
        // SAFETY: valid device; released on drop / in `recreate`.
        unsafe {
            ctx.device
                .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
        }
        .map_err(VkError::vk("create a semaphore"))
    }

    fn check_support(&mut self, ctx: &Context) -> Result<(), VkError> {
        // SAFETY: physical device, queue family and surface belong to this instance.
        let present = unsafe {
            self.surface_loader.get_physical_device_surface_support(
                ctx.physical_device,
                ctx.queue_family,
                self.surface,
            )
        }
        .map_err(VkError::vk("query presentation support"))?;
        if !present {
            return Err(VkError::Invalid(format!(
                "the device {} cannot present to this window; choose another with --device",
                ctx.info.name
            )));
        }
        // SAFETY: as above.
        let formats = unsafe {
            self.surface_loader
                .get_physical_device_surface_formats(ctx.physical_device, self.surface)
        }
        .map_err(VkError::vk("query surface formats"))?;
        self.format = FORMATS
            .iter()
            .copied()
            .find(|f| {
                formats.iter().any(|s| {
                    s.format == *f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
                })
            })
            .ok_or_else(|| {
                VkError::Invalid(format!(
                    "the window offers none of the formats {FORMATS:?} (it offers {:?}); voxgi needs an 8-bit UNORM swapchain",
                    formats.iter().map(|f| f.format).collect::<Vec<_>>()
                ))
            })?;
        Ok(())
    }

    /// The extent the surface wants for a window of `window_px` pixels; zero when minimized.
    pub fn surface_extent(
        &self,
        ctx: &Context,
        window_px: vk::Extent2D,
    ) -> Result<vk::Extent2D, VkError> {
        // SAFETY: physical device and surface are live.
        let caps = unsafe {
            self.surface_loader
                .get_physical_device_surface_capabilities(ctx.physical_device, self.surface)
        }
        .map_err(VkError::vk("query surface capabilities"))?;
        Ok(if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: window_px
                    .width
                    .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: window_px
                    .height
                    .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        })
    }

    /// Recreates the swapchain for a window of `window_px` pixels. Waits for the device first.
    /// With a zero extent (minimized) the old swapchain is kept; check [`Self::extent`].
    pub fn recreate(&mut self, ctx: &Context, window_px: vk::Extent2D) -> Result<(), VkError> {
        let extent = self.surface_extent(ctx, window_px)?;
        if extent.width == 0 || extent.height == 0 {
            self.extent = extent;
            return Ok(());
        }
        ctx.wait_idle()?;
        // SAFETY: as above.
        let caps = unsafe {
            self.surface_loader
                .get_physical_device_surface_capabilities(ctx.physical_device, self.surface)
        }
        .map_err(VkError::vk("query surface capabilities"))?;
        let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps.supported_usage_flags.contains(usage) {
            return Err(VkError::Invalid(format!(
                "the window's swapchain images do not support {usage:?} (they support {:?})",
                caps.supported_usage_flags
            )));
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(self.format)
            .image_color_space(vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            // FIFO is the one mode every driver has; it also keeps the viewer from spinning.
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(self.raw);
        // SAFETY: the surface is live; the old swapchain is retired by this call and released
        // below, after the device went idle (waited above), so it is destroyed at once.
        let raw = unsafe { self.loader.create_swapchain(&info, None) }
            .map_err(VkError::vk("create the swapchain"))?;
        self.release_images();
        let old = std::mem::replace(&mut self.raw, raw);
        self.release
            .release(vec![Garbage::Swapchain(self.loader.clone(), old)]);
        self.extent = extent;
        // SAFETY: raw is the live swapchain just created.
        let raws = unsafe { self.loader.get_swapchain_images(raw) }
            .map_err(VkError::vk("get the swapchain images"))?;
        for (i, &image) in raws.iter().enumerate() {
            let desc = ImageDesc::new_2d(
                &format!("swapchain image {i}"),
                self.format,
                extent.width,
                extent.height,
            )
            .with_usage(usage);
            self.images.push(ctx.wrap_swapchain_image(image, &desc)?);
            let sem = self.semaphore(ctx)?;
            self.render_semaphores.push(sem);
        }
        Ok(())
    }

    /// Acquires the next image, signalling the semaphore of frame slot `slot`. Call after the
    /// slot's fence was waited for (so its semaphore is unsignalled and unused).
    pub fn acquire(&self, slot: usize) -> Result<Acquired, VkError> {
        let ready = self.acquire_semaphores[slot % self.acquire_semaphores.len()];
        // SAFETY: the swapchain is live; `ready` is unsignalled (see above).
        match unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, ready, vk::Fence::null())
        } {
            // A suboptimal image is still presentable: use it, recreate after presenting.
            Ok((index, _suboptimal)) => Ok(Acquired::Image { index, ready }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(vk::Result::ERROR_SURFACE_LOST_KHR) => Ok(Acquired::SurfaceLost),
            Err(e) => Err(VkError::Call {
                what: "acquire a swapchain image",
                result: e,
            }),
        }
    }

    /// The semaphore the frame rendering into image `index` signals and presentation waits on.
    pub fn render_semaphore(&self, index: u32) -> vk::Semaphore {
        self.render_semaphores[index as usize]
    }

    /// Presents image `index`.
    pub fn present(&self, ctx: &Context, index: u32) -> Result<Presented, VkError> {
        let waits = [self.render_semaphore(index)];
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        // SAFETY: the image was acquired and the frame writing it was submitted signalling
        // `waits[0]`; the queue is used from this thread only.
        match unsafe { self.loader.queue_present(ctx.queue, &info) } {
            Ok(false) => Ok(Presented::Done),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented::Recreate),
            Err(vk::Result::ERROR_SURFACE_LOST_KHR) => Ok(Presented::SurfaceLost),
            Err(e) => Err(VkError::Call {
                what: "present",
                result: e,
            }),
        }
    }

    /// Releases the views of the images and the semaphores that go with them.
    fn release_images(&mut self) {
        self.images.clear();
        let semaphores = self.render_semaphores.drain(..).map(Garbage::Semaphore);
        self.release.release(semaphores.collect());
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // Presentation may still wait on the semaphores, and the surface must go before the
        // window: wait for the device, so that everything below is destroyed now, in order
        // (views and semaphores, the swapchain, then its surface).
        self.release.wait_idle();
        self.release_images();
        let mut items: Vec<Garbage> = self
            .acquire_semaphores
            .drain(..)
            .map(Garbage::Semaphore)
            .collect();
        items.push(Garbage::Swapchain(self.loader.clone(), self.raw));
        items.push(Garbage::Surface(self.surface_loader.clone(), self.surface));
        self.release.release(items);
    }
}
