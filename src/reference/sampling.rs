//! Sample generation, a bit-exact port of `shaders/sampling.wgsl`: the same
//! `u32` wrapping arithmetic, so the reference and the GPU place every pixel
//! jitter and every area-light sample at the same point.
//!
//! Stratified samples are the R2 low-discrepancy sequence (Roberts, "The
//! Unreasonable Effectiveness of Quasirandom Sequences", 2018) in 32-bit
//! fixed point, shifted per (pixel, stream, seed) by a hash (Cranley–Patterson
//! rotation); random samples hash every index. The hash is PCG (Jarzynski and
//! Olano, "Hash Functions for GPU Rendering", JCGT 2020).
//!
//! Streams: 0 is the pixel jitter (index = pass), `1 + i` is light `i`
//! (index = pass · samples + j); `pixel` is `y · width + x`.

use crate::frame::Sampler;

/// 2³² / φ₂ and 2³² / φ₂², rounded (φ₂ the plastic number).
const R2_A1: u32 = 3_242_174_889;
const R2_A2: u32 = 2_447_445_414;

/// PCG hash of one `u32` (the RXS-M-XS output of a single LCG step).
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Hash of three `u32`s, nested as in the shader.
pub fn hash3(a: u32, b: u32, c: u32) -> u32 {
    pcg(a ^ pcg(b ^ pcg(c)))
}

/// A hash as a number in [0, 1): its 24 high bits times 2⁻²⁴, exactly an
/// `f32` (the `Blend` alpha test's ξ, [`crate::scene::texture`]).
pub fn unit_float(h: u32) -> f64 {
    (h >> 8) as f64 * (1.0 / 16_777_216.0)
}

/// The 24 high bits of both coordinates of sample `n` of `stream` for
/// `pixel`: the sample is these times 2⁻²⁴.
pub fn sample_2d_bits(sampler: Sampler, seed: u32, pixel: u32, stream: u32, n: u32) -> [u32; 2] {
    match sampler {
        Sampler::Random => {
            let h = hash3(pixel, stream ^ seed.wrapping_mul(0x9e37_79b9), n);
            [h >> 8, pcg(h) >> 8]
        }
        Sampler::Stratified => {
            let h = hash3(pixel, stream, seed);
            [
                n.wrapping_mul(R2_A1).wrapping_add(h) >> 8,
                n.wrapping_mul(R2_A2).wrapping_add(pcg(h)) >> 8,
            ]
        }
    }
}

/// Sample `n` of `stream` for `pixel`, in [0, 1)². Each coordinate has 24
/// significant bits, so it is exactly the shader's `f32` value.
pub fn sample_2d(sampler: Sampler, seed: u32, pixel: u32, stream: u32, n: u32) -> [f64; 2] {
    const SCALE: f64 = 1.0 / 16_777_216.0;
    sample_2d_bits(sampler, seed, pixel, stream, n).map(|b| b as f64 * SCALE)
}

#[cfg(test)]
mod tests {
    use super::*;

    // Values derived step by step from the definitions (all mod 2³²):
    //
    // pcg(0): state = 0·747796405 + 2891336453 = 2891336453; state >> 28 = 10,
    //   so shift 14: state >> 14 = 176473; 176473 ^ 2891336453 = 2891250268;
    //   · 277803737 = 129708028; (129708028 >> 22) ^ 129708028 = 30 ^ 129708028
    //   = 129708002.
    // Stratified, pixel 0, stream 0, seed 0, n 0: h = pcg(0 ^ pcg(0 ^ pcg(0))):
    //   pcg(0) = 129708002; pcg(129708002): state 1305818063, shift 8,
    //   >> 8 = 5100851, xor 1301866236, word 817759132, ^ 194 = 817759070;
    //   pcg(817759070): state 2312855163, shift 12, >> 12 = 564661, xor
    //   2312356814, word 2145236382, ^ 511 = 2145236065 = h.
    //   pcg(h): state 2923555482, shift 14, >> 14 = 178439, xor 2923647901,
    //   word 2368883221, ^ 564 = 2368882721.
    //   n = 0, so the sample is (h >> 8, pcg(h) >> 8) = (8379828, 9253448)·2⁻²⁴.
    // Stratified, pixel 5, stream 1, seed 7, n 3: pcg(7) = 2120684060
    //   (state 3830943992, shift 18); 1 ^ that = 2120684061 → pcg = 2809854175
    //   (state 1160483974, shift 8); 5 ^ that = 2809854170 → pcg = 1476896185
    //   = h (state 2756285223, shift 14); pcg(h) = 1514727946 (state
    //   3343480274, shift 16). x = 3·3242174889 + h = 2613486260 (mod 2³²),
    //   y = 3·2447445414 + 1514727946 = 267129596 (mod 2³²):
    //   (10208930, 1043474)·2⁻²⁴.
    // Random, same tuple: stream ^ seed·0x9e3779b9 = 1 ^ 1401181199 =
    //   1401181198; h = pcg(5 ^ pcg(1401181198 ^ pcg(3))): pcg(3) = 2131687100,
    //   xor → 747283122, pcg → 1874199209, 5 ^ → 1874199212, pcg → 1057333708
    //   = h; pcg(h) = 2922631016: (4130209, 11416527)·2⁻²⁴.
    #[test]
    fn matches_values_derived_by_hand() {
        assert_eq!(pcg(0), 129_708_002);
        assert_eq!(pcg(129_708_002), 817_759_070);
        assert_eq!(hash3(0, 0, 0), 2_145_236_065);
        assert_eq!(
            sample_2d_bits(Sampler::Stratified, 0, 0, 0, 0),
            [8_379_828, 9_253_448]
        );
        assert_eq!(hash3(5, 1, 7), 1_476_896_185);
        assert_eq!(
            sample_2d_bits(Sampler::Stratified, 7, 5, 1, 3),
            [10_208_930, 1_043_474]
        );
        assert_eq!(
            sample_2d_bits(Sampler::Random, 7, 5, 1, 3),
            [4_130_209, 11_416_527]
        );
        let s = sample_2d(Sampler::Stratified, 7, 5, 1, 3);
        assert_eq!(s, [10_208_930.0 / 16_777_216.0, 1_043_474.0 / 16_777_216.0]);
        // Exactly representable in f32: the shader's values.
        assert_eq!(s[0] as f32 as f64, s[0]);
    }

    #[test]
    fn r2_constants_are_the_plastic_number_in_fixed_point() {
        // φ₂ is the real root of x³ = x + 1.
        let mut phi = 1.3_f64;
        for _ in 0..50 {
            phi -= (phi * phi * phi - phi - 1.0) / (3.0 * phi * phi - 1.0);
        }
        let two32 = 4_294_967_296.0;
        assert_eq!((two32 / phi).round() as u32, R2_A1);
        assert_eq!((two32 / (phi * phi)).round() as u32, R2_A2);
    }

    #[test]
    fn stratified_points_fill_the_square_evenly() {
        // 64 consecutive R2 points: every 8×8 cell gets few, none gets many.
        let mut cells = [0u32; 64];
        for n in 0..64 {
            let [x, y] = sample_2d(Sampler::Stratified, 3, 11, 2, n);
            assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
            cells[(y * 8.0) as usize * 8 + (x * 8.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c <= 3), "{cells:?}");
    }
}
