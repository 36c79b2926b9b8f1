//! Texture edits: `penumbra watch` replaces one texture's texels on the
//! device when its file changes, without re-uploading the scene or
//! recompiling anything.

use super::bindings::Bound;
use super::layout::textures::texture_words;
use super::stages::Binding;
use super::{RenderError, Renderer, UploadedScene};
use crate::scene::{Texture, TextureId};

impl Renderer {
    /// Replaces texture `id` of the uploaded scene by `texture`, writing
    /// only that texture's mip chain. The new texture must have the size
    /// and colour space of the old one (its place and its uses' level of
    /// detail depend on them); otherwise this is an error and the caller
    /// uploads the scene again. The next render traces its hits again:
    /// normal maps and alpha cut-outs read textures before shading.
    pub fn replace_texture(
        &mut self,
        scene: &mut UploadedScene,
        id: TextureId,
        texture: &Texture,
    ) -> Result<(), RenderError> {
        let field = format!("textures[{id}] ({})", texture.label);
        let Some(chain) = scene.texture_chains.get(id).copied() else {
            return Err(RenderError::Scene {
                field,
                message: format!("the scene has {} textures", scene.texture_chains.len()),
            });
        };
        if (chain.width, chain.height, chain.srgb) != (texture.width, texture.height, texture.srgb)
            || texture.texels.len() != (texture.width * texture.height) as usize
        {
            return Err(RenderError::Scene {
                field,
                message: format!(
                    "is now {}×{} (was {}×{}): a texture of another size needs the scene uploaded again",
                    texture.width, texture.height, chain.width, chain.height
                ),
            });
        }
        let (mut words, _) = texture_words(texture);
        debug_assert_eq!(words.len(), chain.words);
        words.resize(words.len().next_multiple_of(4), 0);
        let Bound::Image(image) = scene.bound.get(Binding::TextureTexels) else {
            unreachable!("the texture texels are a texel image");
        };
        self.context
            .write_texel_image(image, chain.first_texel, bytemuck::cast_slice(&words))?;
        self.reuse_hits = false;
        Ok(())
    }
}
