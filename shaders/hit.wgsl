// The nearest intersection along a ray, and the normal the ray carries back.

// (The kinds of primitive a ray can hit are in stages/records.wgsl.)

struct Hit {
    found: bool,
    t: f32,
    // Which primitive: kind and index into that kind's buffer.
    kind: u32,
    index: u32,
    // Filled in by finish_hit for the nearest hit only.
    position: vec3<f32>,
    geometric_normal: vec3<f32>,
    shading_normal: vec3<f32>,
    shader: u32,
    // Index of the scene object the primitive belongs to.
    object: u32,
    // Triangles: the barycentric coordinates (u, v) of the hit; planes and
    // spheres: their texture coordinates (filled by surface.wgsl for the
    // nearest hit).
    coords: vec2<f32>,
    // The geometric level of detail of texture coordinate sets 0 and 1
    // (scenes with textures only; surface.wgsl).
    lambda: vec2<f32>,
}

// Nearest hit over every primitive kind the scene has: planes one by one
// (they are infinite), spheres and triangles through the BVH, or one by one
// when the kernel is built without it (the brute-force baseline).
fn closest_hit(ray: Ray) -> Hit {
    var hit: Hit;
    hit.found = false;
    hit.t = FAR;
    if HAS_PLANES {
        for (var i = 0u; i < globals.num_planes; i++) {
            let t = intersect_plane(planes[i], ray);
            if t > 0.0 && t < hit.t {
                hit.found = true;
                hit.t = t;
                hit.kind = KIND_PLANE;
                hit.index = i;
            }
        }
    }
    if USE_BVH {
        bvh_closest(ray, &hit);
    } else {
        if HAS_SPHERES {
            for (var i = 0u; i < globals.num_spheres; i++) {
                closest_sphere(i, ray, &hit);
            }
        }
        if HAS_TRIANGLES {
            for (var i = 0u; i < globals.num_triangles; i++) {
                closest_triangle(i, ray, &hit);
            }
        }
    }
    if hit.found {
        finish_hit(ray, &hit);
    }
    return hit;
}

// Records sphere `i` in `hit` if the ray meets it nearer.
fn closest_sphere(i: u32, ray: Ray, hit: ptr<function, Hit>) {
    let t = intersect_sphere(spheres[i], ray);
    if t > 0.0 && t < (*hit).t {
        (*hit).found = true;
        (*hit).t = t;
        (*hit).kind = KIND_SPHERE;
        (*hit).index = i;
    }
}

// Records triangle `i` in `hit` if the ray meets it nearer.
fn closest_triangle(i: u32, ray: Ray, hit: ptr<function, Hit>) {
    let tri = triangle(i);
    let h = intersect_triangle(tri, ray, (*hit).t);
    if h.x > 0.0 && faces_the_ray(tri, ray) && triangle_is_there(i, tri, h.yz) {
        (*hit).found = true;
        (*hit).t = h.x;
        (*hit).kind = KIND_TRIANGLE;
        (*hit).index = i;
        (*hit).coords = h.yz;
    }
}

// Whether a camera ray sees the triangle: always, but for a single-sided
// one (surface map texel 2's z, glTF's `doubleSided: false`) hit from its
// back, where the ray meets the side its normal (v1 - v0) × (v2 - v0), the
// counter-clockwise front of glTF, points away from. Shadow rays do not ask.
fn faces_the_ray(tri: Triangle, ray: Ray) -> bool {
    // The facing first (the triangle is at hand), the material's flag only
    // for a back face, which camera rays rarely meet.
    if !HAS_SINGLE_SIDED || dot(cross(tri.v1 - tri.v0, tri.v2 - tri.v0), ray.dir) < 0.0 {
        return true;
    }
    return penumbra_surface_map(tri.object, 2u).z == 0u;
}

// Position, normals and shader of the nearest hit. Both normals are turned to
// face the incoming ray: surfaces are two-sided.
fn finish_hit(ray: Ray, hit: ptr<function, Hit>) {
    let p = ray_at(ray, (*hit).t);
    var ng: vec3<f32>;
    var ns: vec3<f32>;
    switch (*hit).kind {
        case KIND_PLANE: {
            let plane = planes[(*hit).index];
            ng = plane.normal;
            ns = ng;
            (*hit).shader = plane.shader;
            (*hit).object = plane.object;
        }
        case KIND_SPHERE: {
            let sphere = spheres[(*hit).index];
            ng = normalize(p - sphere.center);
            ns = ng;
            (*hit).shader = sphere.shader;
            (*hit).object = sphere.object;
        }
        default: {
            let tri = triangle((*hit).index);
            ng = normalize(cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
            ns = triangle_shading_normal(tri, ng, (*hit).coords.x, (*hit).coords.y);
            (*hit).shader = tri.shader;
            (*hit).object = tri.object;
        }
    }
    (*hit).position = p;
    surface_coords(ray, hit, ng);
    if HAS_NORMAL_MAPS && (*hit).kind == KIND_TRIANGLE {
        ns = normal_mapped(*hit, ns);
    }
    if dot(ng, ray.dir) > 0.0 {
        ng = -ng;
    }
    if dot(ns, ray.dir) > 0.0 {
        ns = -ns;
    }
    (*hit).position = p;
    (*hit).geometric_normal = ng;
    (*hit).shading_normal = ns;
}
