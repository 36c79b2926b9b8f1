// The environment's directions (docs/materials.md, "Environment"; the f64
// twin is src/reference/environment.rs): one sample of a fixed mixture of
// densities, weighted by the radiance over the mixture's density (one-sample
// multiple importance sampling), so that the estimate is unbiased whatever
// the shader's BRDF. The light record carries the mixture
// (render::layout::lights, from scene::ENVIRONMENT_MIXTURE): edge1 = the
// weights (uniform sphere, cosine around n, each Phong lobe), edge2 = (the
// first lobe's exponent, the ratio between lobes, the number of lobes).

// exp(y) - 1 without the cancellation of exp near 0 (WGSL has no expm1):
// below |y| = 0.05 the Taylor series to y^4 (truncation < y^4/120, relative).
fn env_expm1(y: f32) -> f32 {
    if abs(y) < 0.05 {
        return y * (1.0 + y * (0.5 + y * (0.16666667 + y * 0.041666668)));
    }
    return exp(y) - 1.0;
}

// ln(1 - x) for x in [0, 1) (WGSL has no log1p): below x = 0.05 the series
// -x(1 + x/2 + x²/3 + x³/4) (truncation < x^4/5, relative).
fn env_log1m(x: f32) -> f32 {
    if x < 0.05 {
        return -x * (1.0 + x * (0.5 + x * (0.33333334 + x * 0.25)));
    }
    return log(1.0 - x);
}

// A unit vector at polar angle θ (sin²θ = s2) and azimuth 2π·u around the
// unit axis `a` (an orthonormal frame of Duff et al. 2017, "Building an
// Orthonormal Basis, Revisited").
fn env_around(a: vec3<f32>, s2: f32, u: f32) -> vec3<f32> {
    let sign = select(-1.0, 1.0, a.z >= 0.0);
    let q = -1.0 / (sign + a.z);
    let t = a.x * a.y * q;
    let b1 = vec3<f32>(1.0 + sign * a.x * a.x * q, sign * t, -sign * a.x);
    let b2 = vec3<f32>(t, sign + a.y * a.y * q, -a.y);
    let sin_t = sqrt(max(0.0, s2));
    let cos_t = sqrt(max(0.0, 1.0 - s2));
    let phi = 6.283185307 * u;
    return normalize(cos_t * a + sin_t * (cos(phi) * b1 + sin(phi) * b2));
}

// The normalised Phong lobe (e+1)/(2π)·cos^e around `r` at `w`, with
// cos^e = exp(e/2 · ln(1 - sin²)) and sin² = |r × w|², which keeps its
// precision near the axis where 1 - cos would not (exponents up to 2^20).
fn env_phong_pdf(r: vec3<f32>, w: vec3<f32>, e: f32) -> f32 {
    if dot(r, w) <= 0.0 {
        return 0.0;
    }
    let c = cross(r, w);
    let s2 = min(dot(c, c), 0.99999994);
    return (e + 1.0) * 0.15915494 * exp(0.5 * e * env_log1m(s2));
}

// The mixture's density at `w` for normal `n` and mirror direction `r`.
fn env_pdf(light: Light, n: vec3<f32>, r: vec3<f32>, w: vec3<f32>) -> f32 {
    var pdf = light.edge1.x * 0.07957747 + light.edge1.y * max(0.0, dot(n, w)) * 0.31830987;
    var e = light.edge2.x;
    for (var k = 0u; k < u32(light.edge2.z); k++) {
        pdf += light.edge1.z * env_phong_pdf(r, w, e);
        e *= light.edge2.y;
    }
    return pdf;
}

// Sample `uv` of environment `light` at a point with unit shading normal `n`
// seen from the unit direction `v` (towards the eye): uv.x picks the
// component and, rescaled, places the sample in it with uv.y. Distance 0: no
// shadow ray, the environment is evaluated without visibility.
fn sample_environment(light: Light, n: vec3<f32>, v: vec3<f32>, uv: vec2<f32>) -> SampledLight {
    let r = normalize(2.0 * dot(n, v) * n - v);
    let wu = light.edge1.x;
    let wc = light.edge1.y;
    var w: vec3<f32>;
    if uv.x < wu {
        // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform.
        let z = 1.0 - 2.0 * (uv.x / wu);
        let s = sqrt(max(0.0, 1.0 - z * z));
        let phi = 6.283185307 * uv.y;
        w = vec3<f32>(s * cos(phi), s * sin(phi), z);
    } else if uv.x < wu + wc {
        // Cosine around n: sin²θ uniform in [0, 1).
        w = env_around(n, min((uv.x - wu) / wc, 1.0), uv.y);
    } else {
        // Phong lobe k: cos θ = (1 - u)^(1/(e+1)), so
        // sin²θ = -expm1(2/(e+1) · ln(1 - u)).
        let t = (uv.x - wu - wc) / light.edge1.z;
        let lobes = u32(light.edge2.z);
        let k = min(u32(t), lobes - 1u);
        let u = min(t - f32(k), 0.99999994);
        var e = light.edge2.x;
        for (var j = 0u; j < k; j++) {
            e *= light.edge2.y;
        }
        w = env_around(r, -env_expm1(2.0 / (e + 1.0) * log(1.0 - u)), uv.y);
    }
    let g = light.cone_offset + light.cone_scale * dot(w, light.direction);
    return SampledLight(w, 0.0, g / (env_pdf(light, n, r, w) * f32(light.samples)));
}
