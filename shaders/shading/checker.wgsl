// The 3D checkerboard: a shader of two sub-shaders, `even` where
// floor(x/s) + floor(y/s) + floor(z/s) is even in world coordinates.
// Positions here are camera-relative, so the host passes the eye position's
// cell split into a fractional offset (`cell_offset`, in cells) and the parity
// of its whole cells (`parity`), computed in f64: the pattern stays exact far
// from the origin.
//
// A surface lying on a cell boundary (the classic plane at y = 0) would pick
// either cell at random from rounding noise; the lookup point is therefore
// moved 1/1000 of a cell into the surface, away from the viewer, which makes
// the choice consistent.
const CHECKER_INSET: f32 = 1e-3;

fn checker_is_even(node: ShaderNode, p: vec3<f32>, n: vec3<f32>) -> bool {
    let cell = floor(p * node.inv_size - CHECKER_INSET * n + node.cell_offset);
    let sum = cell.x + cell.y + cell.z + f32(node.parity);
    return sum - 2.0 * floor(sum * 0.5) == 0.0;
}
