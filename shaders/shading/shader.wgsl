// Shading models as a flat table: Phong, Blinn-Phong, and checkers whose
// sub-shaders are indices into the same table (nesting without recursion).

const SHADER_PHONG: u32 = 0u;
const SHADER_BLINN_PHONG: u32 = 1u;
const SHADER_CHECKER: u32 = 2u;

// Mirrored by render::layout::ShaderNode.
struct ShaderNode {
    ambient: vec3<f32>,
    kind: u32,
    diffuse: vec3<f32>,
    shininess: f32,
    specular: vec3<f32>,
    inv_size: f32,
    cell_offset: vec3<f32>,
    parity: u32,
    even: u32,
    odd: u32,
    _pad: vec2<u32>,
}

@group(0) @binding(6) var<storage, read> shader_nodes: array<ShaderNode>;

// Walks down nested checkers to the Phong or Blinn-Phong shader at `p`
// (`n`: the normal facing the viewer). Validation rules out cycles; the bound
// keeps a bad table from hanging.
fn resolve_shader(id: u32, p: vec3<f32>, n: vec3<f32>) -> ShaderNode {
    var node = shader_nodes[id];
    if HAS_CHECKER {
        for (var depth = 0u; depth < globals.num_shaders && node.kind == SHADER_CHECKER; depth++) {
            node = shader_nodes[select(node.odd, node.even, checker_is_even(node, p, n))];
        }
    }
    return node;
}

// The seminar's sum over lights at a hit:
// k_a·I_a + [visible]·(k_d·I_d·max(0, l·n) + k_s·I_s·lobe), lobe zero where l·n <= 0.
fn shade(ray: Ray, hit: Hit, pixel: u32, shadow_rays: ptr<function, u32>) -> vec3<f32> {
    let node = resolve_shader(hit.shader, hit.position, hit.geometric_normal);
    let n = hit.shading_normal;
    let v = -ray.dir;
    var colour = vec3<f32>(0.0);
    for (var i = 0u; i < globals.num_lights; i++) {
        // The first light without a load (lights.wgsl: first_light). Kept
        // inline: as a function returning the light it was slower.
        var light = first_light;
        if i > 0u {
            light = lights[i];
        }
        // The ambient term counts once per light, also for area lights.
        colour += node.ambient * light.ambient;
        let count = light_sample_count(light);
        for (var j = 0u; j < count; j++) {
            var uv = vec2<f32>(0.5);
            if HAS_AREA_LIGHTS {
                uv = sample_2d(pixel, 1u + i, push.pass_index * count + j);
            }
            let ls = sample_light(light, hit.position, uv);
            let ln = dot(ls.to_light, n);
            // Light below the geometric surface (possible with interpolated
            // normals): the surface itself is in the way, no ray needed.
            if ln <= 0.0 || ls.falloff <= 0.0 || dot(ls.to_light, hit.geometric_normal) <= 0.0 {
                continue;
            }
            *shadow_rays += 1u;
            if occluded(hit, ls) {
                continue;
            }
            var lobe = 0.0;
            if HAS_BLINN_PHONG && node.kind == SHADER_BLINN_PHONG {
                lobe = blinn_phong_lobe(n, ls.to_light, v, node.shininess);
            } else if HAS_PHONG {
                lobe = phong_lobe(n, ls.to_light, v, node.shininess);
            }
            colour += ls.falloff * (node.diffuse * light.diffuse * ln + node.specular * light.specular * lobe);
        }
    }
    return colour;
}
