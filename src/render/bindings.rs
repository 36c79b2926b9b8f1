//! Resources by binding: what a frame binds at each binding of set 0
//! ([`Binding`], [`BINDINGS`]), filled and patched by name. The binding's
//! number is its `Binding`'s discriminant, checked against the table's
//! order (`stages::tests::bindings_are_numbered_in_order`) and against the
//! WGSL's declarations at every compile (`compile::check_bindings`); no
//! other list is kept in step with it.

use super::stages::{Binding, BINDINGS};
use super::RenderError;
use crate::vulkan::{Buffer, Resource, TexelImage, VulkanError};

/// What an uploaded scene binds at one binding.
pub(super) enum Bound {
    Buffer(Buffer),
    Image(TexelImage),
}

impl Bound {
    pub(super) fn resource(&self) -> Resource<'_> {
        match self {
            Bound::Buffer(b) => Resource::Buffer(b),
            Bound::Image(i) => Resource::Image(i),
        }
    }
}

/// One resource for every binding, put in by name.
pub(super) struct BindingSet<T> {
    slots: Vec<Option<T>>,
}

impl<T> BindingSet<T> {
    /// A set with nothing bound yet.
    pub(super) fn new() -> Self {
        BindingSet {
            slots: BINDINGS.iter().map(|_| None).collect(),
        }
    }

    /// Binds `value` at `binding`, replacing what was there.
    pub(super) fn put(&mut self, binding: Binding, value: T) {
        self.slots[binding as usize] = Some(value);
    }

    /// Every binding's value in binding order, or an error naming the first
    /// binding that nothing was put at.
    pub(super) fn complete(self) -> Result<Bindings<T>, RenderError> {
        let mut values = Vec::with_capacity(self.slots.len());
        for (slot, info) in self.slots.into_iter().zip(&BINDINGS) {
            match slot {
                Some(v) => values.push(v),
                None => {
                    return Err(RenderError::Vulkan(VulkanError::InvalidArgument(format!(
                        "nothing is bound at binding {} ({})",
                        info.binding as u32, info.name
                    ))))
                }
            }
        }
        Ok(Bindings { values })
    }
}

/// A complete set: a value at every binding.
#[derive(Clone)]
pub(super) struct Bindings<T> {
    values: Vec<T>,
}

impl<T> Bindings<T> {
    /// The value at `binding`.
    pub(super) fn get(&self, binding: Binding) -> &T {
        &self.values[binding as usize]
    }

    /// Replaces the value at `binding`.
    pub(super) fn set(&mut self, binding: Binding, value: T) {
        self.values[binding as usize] = value;
    }

    /// The values in binding order, as a pipeline's descriptor set takes them.
    pub(super) fn in_binding_order(&self) -> &[T] {
        &self.values
    }

    /// Each value mapped by `f`.
    pub(super) fn map<'a, U>(&'a self, f: impl FnMut(&'a T) -> U) -> Bindings<U> {
        Bindings {
            values: self.values.iter().map(f).collect(),
        }
    }
}

impl Bindings<Bound> {
    /// The buffer at `binding`, for the bindings [`BINDINGS`] declares as
    /// buffers.
    pub(super) fn buffer(&self, binding: Binding) -> Result<&Buffer, RenderError> {
        match self.get(binding) {
            Bound::Buffer(b) => Ok(b),
            Bound::Image(i) => Err(RenderError::Vulkan(VulkanError::InvalidArgument(format!(
                "'{}' is a texel image, not a buffer",
                i.label()
            )))),
        }
    }

    /// The resources to bind, to be patched per render.
    pub(super) fn resources(&self) -> Bindings<Resource<'_>> {
        self.map(Bound::resource)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_is_complete_only_with_every_binding_and_keeps_each_by_name() {
        let mut set = BindingSet::new();
        // Filled in reverse: the order of `put` does not matter.
        for info in BINDINGS.iter().rev() {
            set.put(info.binding, info.name);
        }
        let all = set.complete().unwrap();
        for info in &BINDINGS {
            assert_eq!(*all.get(info.binding), info.name);
        }
        let mut set = BindingSet::new();
        for info in BINDINGS.iter().filter(|b| b.binding != Binding::Params) {
            set.put(info.binding, info.name);
        }
        let e = set.complete().err().unwrap().to_string();
        assert!(e.contains("(params)"), "{e}");
    }
}
