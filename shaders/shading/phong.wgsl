// Phong's specular lobe: max(0, r·v)^n_s with r the mirror of l about n.
// The caller guarantees l·n > 0 (the specular term is zero otherwise).
fn phong_lobe(n: vec3<f32>, l: vec3<f32>, v: vec3<f32>, shininess: f32) -> f32 {
    let r = 2.0 * dot(l, n) * n - l;
    return spec_pow(max(dot(r, v), 0.0), shininess);
}

// x^n with 0^0 = 1 (pow(0, 0) is undefined in WGSL/SPIR-V).
fn spec_pow(x: f32, n: f32) -> f32 {
    if n == 0.0 {
        return 1.0;
    }
    if x <= 0.0 {
        return 0.0;
    }
    return pow(x, n);
}
