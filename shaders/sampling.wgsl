// Sample generation for pixel jitter and area lights.
//
// Stratified samples come from the R2 low-discrepancy sequence (Roberts, "The
// Unreasonable Effectiveness of Quasirandom Sequences", 2018): the n-th point
// is frac(n·(1/φ₂, 1/φ₂²)), φ₂ the plastic number, computed in 32-bit fixed
// point so it stays exact for any n. Each pixel and stream shifts the whole
// sequence by its own random offset (Cranley–Patterson rotation), so pixels
// do not share a pattern; the offsets come from a hash of (pixel, stream,
// seed), making every image a pure function of the scene, the sample counts
// and the seed. The "random" sampler (for comparison) hashes every sample.
//
// Hash: PCG (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020).

const SAMPLER_STRATIFIED: u32 = 0u;
const SAMPLER_RANDOM: u32 = 1u;

// 2³² / φ₂ and 2³² / φ₂², rounded.
const R2_A1: u32 = 3242174889u;
const R2_A2: u32 = 2447445414u;

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn hash3(a: u32, b: u32, c: u32) -> u32 {
    return pcg(a ^ pcg(b ^ pcg(c)));
}

// A u32 as a float in [0, 1) (24 significant bits, so never 1.0).
fn unit_float(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

// Sample `n` of stream `stream` for pixel `pixel`, in [0, 1)².
fn sample_2d(pixel: u32, stream: u32, n: u32) -> vec2<f32> {
    return sample_2d_shifted(sample_shift(pixel, stream), pixel, stream, n);
}

// The stratified sampler's shift of the sequence for pixel `pixel` and
// stream `stream` (unused by the random sampler): the same for every `n`,
// so a loop over the samples of one stream computes it once, outside the
// loop (the shadow stage's light loop does).
fn sample_shift(pixel: u32, stream: u32) -> vec2<u32> {
    let h = hash3(pixel, stream, push.seed);
    return vec2<u32>(h, pcg(h));
}

// sample_2d, given `shift = sample_shift(pixel, stream)`.
fn sample_2d_shifted(shift: vec2<u32>, pixel: u32, stream: u32, n: u32) -> vec2<f32> {
    if SAMPLER == SAMPLER_RANDOM {
        let h = hash3(pixel, stream ^ (push.seed * 0x9e3779b9u), n);
        return vec2<f32>(unit_float(h), unit_float(pcg(h)));
    }
    return vec2<f32>(unit_float(n * R2_A1 + shift.x), unit_float(n * R2_A2 + shift.y));
}
