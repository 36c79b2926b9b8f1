//! Mutations: byte-level ones for any file, structure-aware ones on the JSON
//! tree of glTF documents and JSON scenes, token-level ones for WGSL, and
//! hostile snippets for user shader files.

use serde_json::{Map, Value};

/// SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): small, fast and seedable, so a run is
/// reproducible from its seed.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    /// True with probability `1/n`.
    pub fn one_in(&mut self, n: usize) -> bool {
        self.below(n) == 0
    }
    /// One element of a non-empty slice.
    pub fn pick<'a, T>(&mut self, xs: &'a [T]) -> &'a T {
        &xs[self.below(xs.len())]
    }
}

/// Numbers that find edge cases: zero, signs, powers of two near integer
/// widths, counts near our limits, and values that overflow `f32`.
const NUMBERS: &[f64] = &[
    0.0,
    1.0,
    -1.0,
    2.0,
    3.0,
    4.0,
    7.0,
    12.0,
    255.0,
    256.0,
    65535.0,
    65536.0,
    16777215.0,
    16777216.0,
    2147483647.0,
    2147483648.0,
    4294967295.0,
    4294967296.0,
    9007199254740992.0,
    1.8446744073709552e19,
    1e18,
    1e19,
    1e39,
    1e308,
    -1e308,
    1e-45,
    0.5,
    -0.0,
    3.4028235e38,
];

/// Keys whose values are indices or enums, with values worth trying;
/// `context` is the top-level collection the key sits in (`cameras`, `objects`).
fn key_values(key: &str, context: &str) -> Option<Vec<Value>> {
    let nums = |xs: &[f64]| xs.iter().map(|&x| Value::from(x)).collect();
    let strs = |xs: &[&str]| xs.iter().map(|&x| Value::from(x)).collect();
    Some(match key {
        "componentType" => nums(&[5120.0, 5121.0, 5122.0, 5123.0, 5124.0, 5125.0, 5126.0, 0.0]),
        // `type` means something else in each collection.
        "type" => match context {
            "accessors" => strs(&[
                "SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4", "VEC5",
            ]),
            "cameras" => strs(&["perspective", "orthographic", "fisheye"]),
            "extensions" | "lights" => strs(&[
                "directional",
                "point",
                "spot",
                "rect",
                "sphere",
                "environment",
                "area",
            ]),
            "objects" => strs(&["plane", "sphere", "triangle", "mesh", "cone"]),
            "shaders" => strs(&[
                "phong",
                "blinn_phong",
                "metallic_roughness",
                "specular_glossiness",
                "checker",
                "wgsl",
            ]),
            _ => strs(&["SCALAR", "perspective", "point", "sphere", "phong", "bogus"]),
        },
        "mode" => nums(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]),
        "target" => nums(&[34962.0, 34963.0, 0.0]),
        "uri" => strs(&[
            "/dev/zero",
            "/dev/stdin",
            "/proc/self/mem",
            "fifo.bin",
            "../outside.bin",
            "/etc/passwd",
            "missing.bin",
            "data:application/octet-stream;base64,AAAA",
            "data:application/octet-stream;base64,@@@",
            "data:,",
            "%zz",
            "%2e%2e/x.bin",
            ".",
            "",
        ]),
        "file" => strs(&[
            "bunny.glb",
            "../bunny.glb",
            "/dev/zero",
            "fifo.bin",
            "",
            ".",
            "x.gltf",
        ]),
        "projection" => strs(&["perspective", "orthographic", "fisheye"]),
        _ => return None,
    })
}

/// A random value of the tree, as a path of keys and indices: from the
/// root, stop at a container with probability 1/(children + 1), else go
/// into a random child. Every value can be reached, and no list of all
/// paths is built (that dominated the time of a case).
fn random_path(v: &Value, rng: &mut Rng) -> Vec<Step> {
    let mut path = Vec::new();
    let mut at = v;
    loop {
        let n = match at {
            Value::Object(m) => m.len(),
            Value::Array(a) => a.len(),
            _ => 0,
        };
        if n == 0 || rng.one_in(n + 1) {
            return path;
        }
        let i = rng.below(n);
        at = match at {
            Value::Object(m) => {
                let (k, child) = m.iter().nth(i).expect("i < len");
                path.push(Step::Key(k.clone()));
                child
            }
            Value::Array(a) => {
                path.push(Step::Index(i));
                &a[i]
            }
            _ => return path,
        };
    }
}

/// One step of a path into a JSON tree.
#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

fn get<'v>(v: &'v Value, path: &[Step]) -> Option<&'v Value> {
    let mut at = v;
    for s in path {
        at = match s {
            Step::Key(k) => at.as_object()?.get(k)?,
            Step::Index(i) => at.as_array()?.get(*i)?,
        };
    }
    Some(at)
}

fn get_mut<'v>(v: &'v mut Value, path: &[Step]) -> Option<&'v mut Value> {
    let mut at = v;
    for s in path {
        at = match s {
            Step::Key(k) => at.as_object_mut()?.get_mut(k)?,
            Step::Index(i) => at.as_array_mut()?.get_mut(*i)?,
        };
    }
    Some(at)
}

fn last_key(path: &[Step]) -> Option<&str> {
    path.iter().rev().find_map(|s| match s {
        Step::Key(k) => Some(k.as_str()),
        Step::Index(_) => None,
    })
}

/// Snippets that glTF readers get wrong, spliced into objects.
fn snippet(rng: &mut Rng) -> (String, Value) {
    use serde_json::json;
    let choices = [
        (
            "sparse",
            json!({"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}),
        ),
        ("camera", json!(0)),
        ("mesh", json!(0)),
        ("children", json!([0])),
        (
            "matrix",
            json!([0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]),
        ),
        ("rotation", json!([0, 0, 0, 0])),
        ("scale", json!([1e30, 1e30, 1e30])),
        ("byteStride", json!(4)),
        (
            "extensionsUsed",
            json!(["KHR_lights_punctual", "KHR_texture_transform"]),
        ),
        ("extensionsRequired", json!(["KHR_draco_mesh_compression"])),
        (
            "extensions",
            json!({"KHR_lights_punctual": {"lights": [{"type": "spot", "spot": {}}, {"type": "point", "range": 0}]}}),
        ),
        ("extensions", json!({"KHR_lights_punctual": {"light": 7}})),
        (
            "cameras",
            json!([{"type": "orthographic", "perspective": {"yfov": 0.5, "znear": 0.1}}]),
        ),
        (
            "cameras",
            json!([{"type": "perspective", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0, "zfar": 1}}]),
        ),
        ("material", json!(5)),
        (
            "materials",
            json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 3}}}]),
        ),
        ("textures", json!([{"source": 9, "sampler": 9}])),
        ("samplers", json!([{"wrapS": 1, "magFilter": 3}])),
        (
            "images",
            json!([{"uri": "/dev/zero"}, {"bufferView": 99, "mimeType": "image/png"}]),
        ),
        (
            "animations",
            json!([{"channels": [{"sampler": 5, "target": {"node": 99, "path": "weights"}}], "samplers": []}]),
        ),
        (
            "skins",
            json!([{"joints": [99], "inverseBindMatrices": 99}]),
        ),
        ("targets", json!([{"POSITION": 99}])),
        ("transform", json!({"scale": [0, 0, 0]})),
        ("transform", json!({"rotate": [1e308, 0, 0], "scale": -1})),
        ("samples", json!(4294967295u64)),
    ];
    let (k, v) = rng.pick(&choices).clone();
    (k.to_string(), v)
}

/// Applies one to four structure-aware mutations to a JSON tree.
pub fn mutate_json(v: &mut Value, donors: &[Value], rng: &mut Rng) {
    for _ in 0..1 + rng.below(4) {
        let path = random_path(v, rng);
        let key = last_key(&path).map(str::to_string);
        let context = match path.first() {
            Some(Step::Key(k)) => k.clone(),
            _ => String::new(),
        };
        let Some(target) = get_mut(v, &path) else {
            continue;
        };
        match rng.below(12) {
            // A number at an edge, or a small change of the one there.
            0 | 1 => {
                *target = match target.as_f64() {
                    Some(x) if rng.one_in(2) => Value::from(x + (rng.below(5) as f64 - 2.0)),
                    _ => Value::from(*rng.pick(NUMBERS)),
                }
            }
            // A value meant for this key (enums, indices, URIs).
            2 | 3 => {
                if let Some(vals) = key.as_deref().and_then(|k| key_values(k, &context)) {
                    *target = rng.pick(&vals).clone();
                } else if target.is_u64() {
                    *target = Value::from(rng.below(8) as u64);
                }
            }
            // Remove a member or an element.
            4 => match target {
                Value::Object(m) if !m.is_empty() => {
                    let k = m
                        .keys()
                        .nth(rng.below(m.len()))
                        .cloned()
                        .unwrap_or_default();
                    m.remove(&k);
                }
                Value::Array(a) if !a.is_empty() => {
                    a.remove(rng.below(a.len()));
                }
                _ => *target = Value::Null,
            },
            // Duplicate elements: more instances, more primitives.
            5 => {
                if let Value::Array(a) = target {
                    if let Some(x) = a.get(rng.below(a.len().max(1))).cloned() {
                        for _ in 0..1 + rng.below(16) {
                            a.push(x.clone());
                        }
                    }
                }
            }
            // A snippet that readers get wrong, here or at the root.
            6 | 7 => {
                let (k, s) = snippet(rng);
                let at = if rng.one_in(2) { &mut *v } else { target };
                if let Value::Object(m) = at {
                    m.insert(k, s);
                }
            }
            // A subtree from a donor document (another seed).
            8 => {
                if !donors.is_empty() {
                    let donor = rng.pick(donors);
                    let at = random_path(donor, rng);
                    if let Some(sub) = get(donor, &at) {
                        *target = sub.clone();
                    }
                }
            }
            // Another type in the same place.
            9 => {
                *target = match rng.below(6) {
                    0 => Value::Null,
                    1 => Value::Bool(true),
                    2 => Value::from("x"),
                    3 => Value::Array(vec![]),
                    4 => Value::Object(Map::new()),
                    _ => Value::from(-1),
                }
            }
            // Deep nesting.
            10 => {
                let mut x = target.take();
                for _ in 0..rng.below(300) {
                    x = Value::Array(vec![x]);
                }
                *target = x;
            }
            // A very long string or array.
            _ => {
                *target = if rng.one_in(2) {
                    Value::from("A".repeat(rng.below(1 << 16)))
                } else {
                    Value::Array(vec![Value::from(0); rng.below(1 << 12)])
                }
            }
        }
    }
}

/// Applies one to eight byte-level mutations: bit flips, interesting bytes,
/// insertions, deletions, repeated blocks, truncation and splices.
pub fn mutate_bytes(data: &mut Vec<u8>, donors: &[Vec<u8>], rng: &mut Rng) {
    for _ in 0..1 + rng.below(8) {
        let len = data.len();
        match rng.below(8) {
            0 if len > 0 => {
                let i = rng.below(len);
                data[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = *rng.pick(&[
                    0u8, 0xff, 0x7f, 0x80, b'"', b'{', b'}', b'[', b',', b'0', b'9', b'-', b'e',
                ]);
            }
            2 => {
                let i = rng.below(len + 1);
                let n = 1 + rng.below(16);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                data.splice(i..i, bytes);
            }
            3 if len > 0 => {
                let i = rng.below(len);
                let n = (1 + rng.below(64)).min(len - i);
                data.drain(i..i + n);
            }
            4 if len > 0 => {
                let i = rng.below(len);
                let n = (1 + rng.below(256)).min(len - i);
                let block = data[i..i + n].to_vec();
                for _ in 0..1 + rng.below(8) {
                    data.splice(i..i, block.iter().copied());
                }
            }
            5 if len > 0 => data.truncate(rng.below(len)),
            6 if len >= 4 => {
                // A little-endian word at an edge (GLB lengths, chunk types).
                let i = rng.below(len - 3);
                let w = *rng.pick(&[
                    0u32,
                    1,
                    2,
                    12,
                    0x7fff_ffff,
                    0xffff_ffff,
                    len as u32,
                    0x4E4F_534A,
                ]);
                data[i..i + 4].copy_from_slice(&w.to_le_bytes());
            }
            7 if !donors.is_empty() => {
                let d = rng.pick(donors);
                if !d.is_empty() {
                    let a = rng.below(d.len());
                    let b = a + rng.below((d.len() - a).min(512) + 1);
                    let i = rng.below(len + 1);
                    data.splice(i..i, d[a..b].iter().copied());
                }
            }
            _ => {}
        }
    }
}

/// Sets an OpenEXR part's display and data windows to sizes at an edge,
/// kept consistent with each other (the data window is the top half, tile
/// 0 of 2), so that the file passes the header checks and reaches the
/// pixel reader with the window it claims.
pub fn mutate_exr_windows(data: &mut [u8], rng: &mut Rng) {
    let sides: [i64; 9] = [1, 2, 16, 17, 16384, 16385, 46341, 1 << 20, i32::MAX as i64];
    let (w, h) = (*rng.pick(&sides), *rng.pick(&sides) & !1);
    let h = h.max(2);
    let mut set = |name: &[u8], b: [i64; 4]| {
        let key = [name, b"\0box2i\0"].concat();
        let Some(i) = data.windows(key.len()).position(|x| x == key.as_slice()) else {
            return;
        };
        let at = i + key.len() + 4;
        if let Some(slot) = data.get_mut(at..at + 16) {
            for (k, v) in b.iter().enumerate() {
                let v = (*v).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
                slot[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
    };
    set(b"displayWindow", [0, 0, w - 1, h - 1]);
    set(b"dataWindow", [0, 0, w - 1, h / 2 - 1]);
}

/// Applies one to four token-level mutations to WGSL: a token replaced by
/// another from the same text, a line deleted, duplicated or swapped, an
/// operator or literal at an edge, or deep nesting.
pub fn mutate_wgsl(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        lines.push(String::new());
    }
    let tokens: Vec<&str> = text
        .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == '.'))
        .filter(|t| !t.is_empty())
        .collect();
    for _ in 0..1 + rng.below(4) {
        let n = lines.len();
        let i = rng.below(n);
        match rng.below(7) {
            0 => {
                lines.remove(i);
                if lines.is_empty() {
                    lines.push(String::new());
                }
            }
            1 => {
                let l = lines[i].clone();
                lines.insert(i, l);
            }
            2 => lines.swap(i, rng.below(n)),
            3 | 4 if !tokens.is_empty() => {
                let words: Vec<String> = lines[i].split(' ').map(str::to_string).collect();
                if !words.is_empty() {
                    let mut words = words;
                    let w = rng.below(words.len());
                    words[w] = rng.pick(&tokens).to_string();
                    lines[i] = words.join(" ");
                }
            }
            5 => {
                let edge = *rng.pick(&[
                    "0",
                    "-1",
                    "1e39",
                    "4294967296u",
                    "-2147483649i",
                    "0x",
                    "1e",
                    "(",
                    ")",
                    "{",
                    "}",
                    ";",
                    "vec3<f32>(",
                    "array<f32, 0>",
                    "array<f32, 4294967295>",
                    "@",
                    "//",
                    "/*",
                    "fn",
                    "let",
                    "var",
                    "loop {",
                    "return",
                    "&",
                    "*",
                    "<<",
                    "%",
                    "..",
                    "\u{0}",
                ]);
                let at = rng.below(lines[i].len() + 1);
                let at = (0..=at)
                    .rev()
                    .find(|&k| lines[i].is_char_boundary(k))
                    .unwrap_or(0);
                lines[i].insert_str(at, edge);
            }
            _ => {
                let depth = rng.below(400);
                lines[i] = format!("{}{}{}", "(".repeat(depth), lines[i], ")".repeat(depth));
            }
        }
    }
    lines.join("\n")
}

/// Characters of more than one byte (two, three and four bytes, a
/// zero-width space, a combining mark).
const MULTIBYTE: &[&str] = &["é", "ß", "日本", "🦀", "\u{200b}", "e\u{301}", "\u{feff}"];

/// A user shader file mutated: on half the cases the token-level mutations
/// of [`mutate_wgsl`], then one to three hostile snippets at random lines:
/// multibyte characters (in block or line comments, or bare, or at the end),
/// comments opened or closed, deep nesting, long loops, big arrays, long
/// sums, declared resources and overrides without a value.
pub fn mutate_shader(text: &str, rng: &mut Rng) -> String {
    let text = if rng.one_in(2) {
        mutate_wgsl(text, rng)
    } else {
        text.to_string()
    };
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for _ in 0..1 + rng.below(3) {
        let snippet = hostile_snippet(rng);
        if rng.one_in(8) {
            lines.push(snippet);
        } else {
            let i = rng.below(lines.len() + 1);
            lines.insert(i, snippet);
        }
    }
    let mut out = lines.join("\n");
    if rng.one_in(4) {
        // Ends without a line break, possibly inside a character's comment.
        let comment: &&str = rng.pick(&["/* ", "// ", ""]);
        let character: &&str = rng.pick(MULTIBYTE);
        out.push_str(comment);
        out.push_str(character);
    }
    out
}

/// One hostile line for [`mutate_shader`].
fn hostile_snippet(rng: &mut Rng) -> String {
    let multibyte = *rng.pick(MULTIBYTE);
    let n = *rng.pick(&[1u64, 16, 31, 32, 33, 200, 2000]) as usize;
    let count = *rng.pick(&[0u64, 1, 4096, 4097, 1_000_000, 100_000_000, 4_294_967_295]);
    match rng.below(10) {
        0 => format!("/* {multibyte} */"),
        1 => format!("// {multibyte}{multibyte}"),
        2 => format!("/* /* {multibyte} */ {multibyte}"),
        3 => format!("{multibyte} */ {multibyte} /*"),
        4 => {
            let (open, close) = *rng.pick(&[("(", ")"), ("[", "]"), ("{", "}")]);
            format!("    let x = {}1.0{};", open.repeat(n), close.repeat(n))
        }
        5 => (*rng.pick(&[
            "    for (var i = 0u; i < 4294967295u; i++) { }",
            "    loop { }",
            "    while true { }",
            "    for (var i = 0; i < 100000000; i++) { for (var j = 0; j < 100000000; j++) { } }",
        ]))
        .to_string(),
        6 => format!(
            "    {} a: array<f32, {count}>;",
            rng.pick(&["var", "var<private>", "var<workgroup>", "let"])
        ),
        7 => format!(
            "{} a{count}: array<vec4<f32>, {count}>;",
            rng.pick(&["var<private>", "var<workgroup>"])
        ),
        8 => format!("    return {}s.normal;", "s.normal + ".repeat(n * 8)),
        _ => (*rng.pick(&[
            "@group(0) @binding(3) var<storage, read_write> counters: array<u32>;",
            "override penumbra_gain: f32;",
            "override gain: f32;",
            "struct Params {}",
            "    let d = dpdx(s.position.x);",
        ]))
        .to_string(),
    }
}
