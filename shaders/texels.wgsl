// Texel images: arrays of 16-byte records that the host stores as the texels
// of a read-only storage image (vulkan::TexelImage), vulkan::TEXEL_ROW texels
// a row. Records every traversal step or triangle test reads live there, not
// in storage buffers: lavapipe loads a storage buffer at a per-lane address
// as a loop over the SIMD lanes, with branches per lane and per word, while
// its storage-image load is straight-line SIMD code (docs/bench.md §6).

// vulkan::TEXEL_ROW and its base-2 logarithm.
const TEXEL_ROW: u32 = 4096u;
const TEXEL_ROW_SHIFT: u32 = 12u;

// The coordinates of texel `i`.
fn texel(i: u32) -> vec2<u32> {
    return vec2<u32>(i & (TEXEL_ROW - 1u), i >> TEXEL_ROW_SHIFT);
}
