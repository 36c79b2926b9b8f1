//! What a renderer is opened with ([`RendererOptions`]) and what one render
//! asks for ([`RenderRequest`], whose constructors are the common requests)
//! and gives ([`Rendered`]).

use std::time::Duration;

use super::{Aovs, Frame, KernelOptions, PartRange, PassInfo, Sampling, ShaderSource};
use crate::vulkan::DeviceSelector;

/// How to set up a [`super::Renderer`].
#[derive(Clone, Debug, Default)]
pub struct RendererOptions {
    /// Which Vulkan device; `None` picks the first discrete or integrated
    /// GPU, else the CPU device (lavapipe).
    pub device: Option<DeviceSelector>,
    /// Enable the Khronos validation layer and fail on any error it reports.
    pub validation: bool,
    /// Where the WGSL comes from.
    pub shaders: ShaderSource,
    /// BVH or brute force, and the ray/triangle test.
    pub kernel: KernelOptions,
    /// The longest one submission may run ([`super::Renderer::set_time_limit`]);
    /// `None`: [`crate::vulkan::DEFAULT_TIME_LIMIT`].
    pub time_limit: Option<Duration>,
}

/// One render of an uploaded scene ([`super::Renderer::render`]): size,
/// samples, which part, which outputs, and the caller's hooks.
pub struct RenderRequest<'a> {
    /// Image width, pixels (at most the uploaded size; smaller keeps the
    /// field of view: previews).
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel, seed and time budget.
    pub sampling: Sampling,
    /// Only these rows and passes of the full-size render (then width and
    /// height must be the uploaded size, and the image is the passes' sum).
    pub part: Option<PartRange>,
    /// Also return the AOVs of each pixel's first primary ray.
    pub aovs: bool,
    /// Called after every pass.
    pub on_pass: Option<&'a mut dyn FnMut(&PassInfo)>,
    /// Asked between bands of rows; a yes stops the render
    /// ([`super::RenderError::Cancelled`]).
    pub cancel: Option<&'a mut dyn FnMut() -> bool>,
}

impl<'a> RenderRequest<'a> {
    /// One sample per pixel through its centre at `width`×`height` (at most
    /// the uploaded size; smaller sizes keep the field of view: previews),
    /// the whole image, no AOVs, no hooks.
    pub fn new(width: u32, height: u32) -> Self {
        RenderRequest {
            width,
            height,
            sampling: Sampling::default(),
            part: None,
            aovs: false,
            on_pass: None,
            cancel: None,
        }
    }

    /// Passes of one sample per pixel each, accumulated in a float buffer,
    /// until `sampling.spp` passes are done or the time budget is spent (the
    /// pass in flight is finished), calling `on_pass` after every pass. The
    /// image is the mean of the passes done.
    pub fn progressive(
        width: u32,
        height: u32,
        sampling: &Sampling,
        on_pass: &'a mut dyn FnMut(&PassInfo),
    ) -> Self {
        RenderRequest {
            sampling: *sampling,
            on_pass: Some(on_pass),
            ..RenderRequest::new(width, height)
        }
    }

    /// [`RenderRequest::progressive`] that also returns the arbitrary output
    /// variables of each pixel's first primary ray.
    pub fn with_aovs(
        width: u32,
        height: u32,
        sampling: &Sampling,
        on_pass: &'a mut dyn FnMut(&PassInfo),
    ) -> Self {
        RenderRequest {
            aovs: true,
            ..RenderRequest::progressive(width, height, sampling, on_pass)
        }
    }

    /// One part of a full-size render of an image `size` pixels large: the
    /// rows and passes of `part` (pass indices out of `sampling.spp`, which
    /// also decides the pixel jitter as in the undivided render). The image
    /// holds only those rows, each pixel the *sum* of the part's passes.
    pub fn part(
        size: (u32, u32),
        part: &PartRange,
        sampling: &Sampling,
        on_pass: &'a mut dyn FnMut(&PassInfo),
    ) -> Self {
        RenderRequest {
            part: Some(part.clone()),
            ..RenderRequest::progressive(size.0, size.1, sampling, on_pass)
        }
    }

    /// One sample per pixel at `width`×`height` in bands of rows, asking
    /// `cancel` between bands: hot reload, where a newer edit stops the
    /// refinement in flight.
    pub fn cancellable(width: u32, height: u32, cancel: &'a mut dyn FnMut() -> bool) -> Self {
        RenderRequest {
            cancel: Some(cancel),
            ..RenderRequest::new(width, height)
        }
    }
}

/// What [`super::Renderer::render`] returns.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image and its statistics.
    pub frame: Frame,
    /// The AOVs, when asked for.
    pub aovs: Option<Aovs>,
}
