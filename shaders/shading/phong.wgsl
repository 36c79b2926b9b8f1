// Phong (Phong 1975, in the seminar's form): for each light,
//   k_a·I_a + [visible]·I·(k_d·I_d·max(0, l·n) + k_s·I_s·max(0, r·v)^n_s)
// with r the mirror of l about n. A shader file like any user's
// (shading/interface.wgsl); the JSON type `phong` maps to it.

struct Params {
    ambient: vec3<f32>,
    diffuse: vec3<f32>,
    specular: vec3<f32>,
    shininess: f32,
    // Textures that scale the reflectances (0xffffffffu: none).
    ambient_texture: u32,
    diffuse_texture: u32,
    specular_texture: u32,
}

// Once per point: the textures and the vertex colour scale the
// reflectances (glTF's base colour is factor × texture × COLOR_0).
fn prepare(s: Surface, p: Params) -> Params {
    var q = p;
    q.ambient = p.ambient * texture_at(p.ambient_texture, s).rgb;
    q.diffuse = p.diffuse * texture_at(p.diffuse_texture, s).rgb * s.colour.rgb;
    q.specular = p.specular * texture_at(p.specular_texture, s).rgb;
    return q;
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.ambient * light_ambient;
}

// The engine calls this only for samples with l·n > 0.
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let ln = dot(l.to_light, s.normal);
    let r = 2.0 * ln * s.normal - l.to_light;
    let lobe = spec_pow(max(dot(r, s.to_eye), 0.0), p.shininess);
    return l.intensity * (p.diffuse * l.diffuse * ln + p.specular * l.specular * lobe);
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
