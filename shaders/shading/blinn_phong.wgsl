// Blinn-Phong's specular lobe: max(0, h·n)^n_s with h = normalize(l + v).
// The caller guarantees l·n > 0 (the specular term is zero otherwise).
fn blinn_phong_lobe(n: vec3<f32>, l: vec3<f32>, v: vec3<f32>, shininess: f32) -> f32 {
    let sum = l + v;
    let len2 = dot(sum, sum);
    if len2 == 0.0 {
        return spec_pow(0.0, shininess);
    }
    return spec_pow(max(dot(sum * inverseSqrt(len2), n), 0.0), shininess);
}
