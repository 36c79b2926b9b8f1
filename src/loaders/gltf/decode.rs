//! The glTF file's images, decoded after the walk, all at once on rayon's
//! threads (issue 39: a large textured asset spent most of its load in one
//! image decode after another). Each image's header was checked and its
//! memory charged while the walk met it ([`crate::loaders::texture::prepare`]); decoding
//! them together holds every decoder's transient memory at once, so they
//! go in parallel only when the budget holds all of it, else one after
//! another. The first failure in file order is reported.

use std::path::PathBuf;

use rayon::prelude::*;

use super::{Reader, Result};
use crate::loaders::texture::Pending;
use crate::scene::{Texture, TextureId};

/// The texture an image becomes until it is decoded.
pub(super) fn placeholder(file: Option<PathBuf>) -> Texture {
    Texture {
        label: String::new(),
        file,
        width: 0,
        height: 0,
        texels: Vec::new(),
        srgb: false,
    }
}

/// Decodes `pending` into their places in `textures`.
pub(super) fn images(
    r: &Reader,
    pending: Vec<(TextureId, Pending, String)>,
    textures: &mut [Texture],
) -> Result<()> {
    let transient: u64 = pending.iter().map(|(_, p, _)| p.transient).sum();
    let decode = |(id, p, at): (TextureId, Pending, String)| (id, p.decode(), at);
    let decoded: Vec<_> = match r.guard.fits(transient) {
        true => pending.into_par_iter().map(decode).collect(),
        false => pending.into_iter().map(decode).collect(),
    };
    for (id, result, at) in decoded {
        let mut t = result.map_err(|e| r.err(at, e.0))?;
        t.file = textures[id].file.take();
        textures[id] = t;
    }
    Ok(())
}
