#!/usr/bin/env python3
"""The benchmark's peers: Mitsuba 3 and Embree 4 on penumbra's benchmark scene.

Each peer builds its scene from the same glTF file as penumbra (the meshes in
world space, the camera node's position, orientation and vertical field of
view, the KHR_lights_punctual directional light) at the same image size and
thread count, and traces one primary ray through every pixel centre and one
shadow ray per hit towards the light:

  mitsuba-llvm    Mitsuba 3 `llvm_ad_rgb`: a whole frame of the `direct`
                  integrator (one emitter sample, no BSDF sample), a
                  non-jittered stratified sampler (pixel centres) and a box
                  filter; Dr.Jit's LLVM back end needs a libLLVM shared library
                  (DRJIT_LIBLLVM_PATH, else the newest /usr/lib/*/libLLVM*.so*).
  mitsuba-scalar  the same frame in Mitsuba's `scalar_rgb` variant.
  embree-single   Embree 4 ray queries, one ray at a time (rtcIntersect1,
                  rtcOccluded1), no shading.
  embree-packets  the same rays as packets of the widest width this Embree
                  build runs natively on this CPU (16 rays, 4x4 pixels, with
                  AVX-512; 8 rays, 4x2 pixels, with AVX2), no shading.

The Embree peers run embree_frame.c (beside this file), compiled on first use
against the libembree4 that the PyPI package embreex ships; embreex's own
single-ray API traces the primary rays once more at start-up, as a check of
the compiled code's hit count.

Usage:
  peers.py run PEER... [--frames N]   print one JSON line per frame and peer
  peers.py serve PEER                 for tools/measure/bench/main.rs: one JSON line with
                                      the peer's facts and counts when ready,
                                      then one line {"frame_ms": ...} per
                                      "frame" line read from stdin
  peers.py versions                   the peers' package versions as JSON

With PENUMBRA_PEERS_ISA=avx2 in the environment (the benchmark sets it, with
GALLIUM_OVERRIDE_CPU_CAPS=avx for lavapipe, to compare AVX2 code on an AVX-512
machine), Dr.Jit's LLVM back end targets the host CPU with every AVX-512
feature disabled and 8-wide vectors, and Embree's device is configured with
isa=avx2; `mitsuba-scalar` is precompiled and stays as it is.

Every line printed on stdout is one JSON object. Counts: `hits` (primary rays
that hit), `shadow_rays` (shadow rays cast) and `blocked` (shadow rays that
hit something), where the peer can tell them.
"""

import argparse
import glob
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))  # tools/measure/peers/ is three below the root
PEERS = ["mitsuba-llvm", "mitsuba-scalar", "embree-single", "embree-packets"]


# ----------------------------------------------------------------- glTF


def quat_matrix(q):
    x, y, z, w = q
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]


def node_matrix(node):
    """The node's local 4x4 transform (row-major lists)."""
    if "matrix" in node:
        m = node["matrix"]  # column-major
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    r = quat_matrix(node.get("rotation", [0, 0, 0, 1]))
    s = node.get("scale", [1, 1, 1])
    t = node.get("translation", [0, 0, 0])
    return [[r[i][j] * s[j] for j in range(3)] + [t[i]] for i in range(3)] + [
        [0, 0, 0, 1]
    ]


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def apply(m, v, w):
    return [sum(m[i][j] * v[j] for j in range(3)) + m[i][3] * w for i in range(3)]


def normalize(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


class Scene:
    """What the peers need of a glTF scene: meshes in world space (float32
    positions, uint32 triangles), the camera and the directional light."""

    def __init__(self, path, width, height):
        import numpy as np

        with open(path, "rb") as f:
            data = f.read()
        if data[:4] != b"glTF":
            raise SystemExit(f"{path}: not a binary glTF (.glb) file")
        (json_len,) = struct.unpack_from("<I", data, 12)
        doc = json.loads(data[20 : 20 + json_len])
        off = 20 + json_len
        (bin_len,) = struct.unpack_from("<I", data, off)
        blob = data[off + 8 : off + 8 + bin_len]
        dtypes = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}
        sizes = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}

        def accessor(i):
            a = doc["accessors"][i]
            view = doc["bufferViews"][a["bufferView"]]
            start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
            n = a["count"] * sizes[a["type"]]
            arr = np.frombuffer(blob, dtypes[a["componentType"]], n, start)
            return arr.reshape(a["count"], sizes[a["type"]])

        self.meshes = []  # (name, positions (n,3) f32, triangles (m,3) u32)
        self.camera = None
        self.light = None
        self.width, self.height = width, height

        def visit(i, parent):
            node = doc["nodes"][i]
            m = mat_mul(parent, node_matrix(node))
            if "mesh" in node:
                mesh = doc["meshes"][node["mesh"]]
                for p in mesh["primitives"]:
                    if p.get("mode", 4) != 4:
                        continue
                    pos = accessor(p["attributes"]["POSITION"]).astype(np.float64)
                    pos = pos @ np.array([r[:3] for r in m[:3]]).T + np.array(
                        [r[3] for r in m[:3]]
                    )
                    idx = accessor(p["indices"]).reshape(-1, 3).astype(np.uint32)
                    self.meshes.append(
                        (mesh.get("name", "mesh"), pos.astype(np.float32), idx)
                    )
            if "camera" in node and self.camera is None:
                cam = doc["cameras"][node["camera"]]["perspective"]
                hh = math.tan(cam["yfov"] / 2)
                self.camera = {
                    "eye": apply(m, [0, 0, 0], 1),
                    "forward": normalize(apply(m, [0, 0, -1], 0)),
                    "up": normalize(apply(m, [0, 1, 0], 0)),
                    "right": normalize(apply(m, [1, 0, 0], 0)),
                    "yfov": cam["yfov"],
                    "half_height": hh,
                    "half_width": hh * width / height,
                }
            light = node.get("extensions", {}).get("KHR_lights_punctual")
            if light is not None and self.light is None:
                spec = doc["extensions"]["KHR_lights_punctual"]["lights"][light["light"]]
                if spec["type"] != "directional":
                    raise SystemExit(f"{path}: the peers handle a directional light only")
                travel = normalize(apply(m, [0, 0, -1], 0))
                self.light = {
                    "to_light": [-x for x in travel],
                    "intensity": spec.get("intensity", 1.0),
                    "color": spec.get("color", [1, 1, 1]),
                }
            for c in node.get("children", []):
                visit(c, m)

        identity = [[float(i == j) for j in range(4)] for i in range(4)]
        for i in doc["scenes"][doc.get("scene", 0)]["nodes"]:
            visit(i, identity)
        if self.camera is None or self.light is None:
            raise SystemExit(f"{path}: needs a perspective camera and a directional light")

    def merged(self):
        """All meshes as one: positions (n,3) f32, triangles (m,3) u32."""
        import numpy as np

        pos, tris, base = [], [], 0
        for _, p, t in self.meshes:
            pos.append(p)
            tris.append(t + base)
            base += len(p)
        return np.concatenate(pos), np.concatenate(tris).astype(np.uint32)

    def camera_vectors(self):
        c = self.camera
        return (
            c["eye"]
            + c["forward"]
            + [x * c["half_width"] for x in c["right"]]
            + [x * c["half_height"] for x in c["up"]]
        )

    def primary_rays(self):
        """Pixel-centre primary rays (penumbra's camera model), row 0 at the
        top: origins and unit directions, (w*h, 3) float32."""
        import numpy as np

        c = self.camera
        w, h = self.width, self.height
        x = (np.arange(w) + 0.5) / w * 2 - 1
        y = 1 - (np.arange(h) + 0.5) / h * 2
        ny, nx = np.meshgrid(y, x, indexing="ij")
        d = (
            np.array(c["forward"])[None, None, :]
            + nx[..., None] * np.array(c["right"]) * c["half_width"]
            + ny[..., None] * np.array(c["up"]) * c["half_height"]
        ).reshape(-1, 3)
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        o = np.broadcast_to(np.array(c["eye"]), d.shape)
        return np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32)


# ----------------------------------------------------------------- Mitsuba


def llvm_path():
    """The libLLVM for Dr.Jit's LLVM back end: DRJIT_LIBLLVM_PATH, else the
    newest versioned libLLVM in the system's library directories."""
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return os.environ["DRJIT_LIBLLVM_PATH"]

    def version(p):
        digits = "".join(ch if ch.isdigit() else " " for ch in os.path.basename(p)).split()
        return [int(d) for d in digits] or [0]

    found = glob.glob("/usr/lib/*/libLLVM*.so*") + glob.glob("/usr/lib/libLLVM*.so*")
    return max(found, key=version) if found else None


class Mitsuba:
    def __init__(self, scene, variant, threads):
        if variant.startswith("llvm"):
            path = llvm_path()
            if path is None:
                raise RuntimeError("no libLLVM found: install libllvm19 or set DRJIT_LIBLLVM_PATH")
            os.environ["DRJIT_LIBLLVM_PATH"] = path
            self.llvm = path
        else:
            self.llvm = None
        import drjit as dr
        import mitsuba as mi

        mi.set_variant(variant)
        dr.set_thread_count(threads)
        self.dr, self.mi, self.scene_in = dr, mi, scene
        self.version = f"mitsuba {mi.__version__}, drjit {dr.__version__}"
        self.notes = "`direct` integrator, 1 emitter sample, 0 BSDF samples"
        if self.llvm:
            self.version += f", {os.path.basename(os.path.realpath(self.llvm))}"
            self.notes += f"; Dr.Jit's LLVM back end on {os.path.realpath(self.llvm)}"
            if isa() == "avx2":
                self.notes += "; " + drjit_avx2(dr)
        self.tmp = tempfile.TemporaryDirectory()
        c, l = scene.camera, scene.light
        shapes = {}
        for i, (name, pos, tris) in enumerate(scene.meshes):
            ply = os.path.join(self.tmp.name, f"{i}.ply")
            write_ply(ply, pos, tris)
            shapes[f"shape{i}_{name}"] = {
                "type": "ply",
                "filename": ply,
                "face_normals": True,
                "bsdf": {
                    "type": "twosided",
                    "material": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.8}},
                },
            }
        eye = c["eye"]
        target = [e + f for e, f in zip(eye, c["forward"])]
        self.sensor = {
            "type": "perspective",
            "fov_axis": "y",
            "fov": math.degrees(c["yfov"]),
            "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=target, up=c["up"]),
            "sampler": {"type": "stratified", "sample_count": 1, "jitter": False},
            "film": {
                "type": "hdrfilm",
                "width": scene.width,
                "height": scene.height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
                "sample_border": False,
            },
        }
        self.base = {
            "type": "scene",
            "light": {
                "type": "directional",
                "direction": [-x for x in l["to_light"]],
                "irradiance": {"type": "rgb", "value": l["intensity"]},
            },
            "sensor": self.sensor,
            **shapes,
        }
        direct = {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0}
        t0 = time.perf_counter()
        self.scene = mi.load_dict({**self.base, "integrator": direct})
        self.setup_ms = (time.perf_counter() - t0) * 1e3
        self.counts_scene = mi.load_dict(
            {
                **self.base,
                "integrator": {"type": "aov", "aovs": "dd:depth,nn:geo_normal", "img": direct},
            }
        )

    def frame(self):
        img = self.mi.render(self.scene, spp=1, seed=0)
        self.dr.eval(img)
        self.dr.sync_thread()
        return img

    def counts(self):
        """Hits (depth > 0), shadow rays (the direct integrator samples the
        emitter at every hit) and blocked ones: hits whose viewer-facing
        normal faces the light but whose colour is black."""
        import numpy as np

        img = np.array(self.mi.render(self.counts_scene, spp=1, seed=0))
        rgb, depth, normal = img[..., 0:3], img[..., 3], img[..., 4:7]
        hit = depth > 0
        o, d = self.scene_in.primary_rays()
        d = d.reshape(normal.shape)
        to_light = np.array(self.scene_in.light["to_light"])
        facing = np.where((normal * d).sum(-1, keepdims=True) > 0, -normal, normal)
        lit_side = hit & ((facing * to_light).sum(-1) > 0)
        blocked = lit_side & (rgb.max(-1) == 0)
        n_hits = int(hit.sum())
        return {"hits": n_hits, "shadow_rays": n_hits, "blocked": int(blocked.sum())}


def isa():
    """The instruction-set cap the benchmark asks for: "avx2", or "" for the
    best the CPU has."""
    value = os.environ.get("PENUMBRA_PEERS_ISA", "")
    if value not in ("", "avx2"):
        raise SystemExit(f"PENUMBRA_PEERS_ISA: {value!r} is not avx2")
    return value


def drjit_avx2(dr):
    """Makes Dr.Jit's LLVM back end (already initialised by set_variant)
    generate AVX2 code: the host CPU with every AVX-512 feature disabled and
    8-wide vectors, through drjit-core's exported jit_llvm_set_target (its
    Python bindings do not expose it). Returns what it set, read back."""
    import ctypes

    core = ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so"))
    get_cpu = core._Z19jit_llvm_target_cpuv
    get_features = core._Z24jit_llvm_target_featuresv
    get_width = core._Z21jit_llvm_vector_widthv
    get_cpu.restype = get_features.restype = ctypes.c_char_p
    get_width.restype = ctypes.c_uint32
    cpu, features = get_cpu(), get_features() or b""
    capped = b",".join(
        b"-" + f[1:] if f[1:].startswith(b"avx512") else f for f in features.split(b",") if f
    )
    set_target = core._Z19jit_llvm_set_targetPKcS0_j
    set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    set_target(cpu, capped, 8)
    now = get_features() or b""
    if any(f.startswith(b"+avx512") for f in now.split(b",")) or get_width() != 8:
        raise RuntimeError(f"Dr.Jit kept AVX-512: features {now.decode()}, width {get_width()}")
    return f"AVX2 code: target {get_cpu().decode()} with AVX-512 disabled, {get_width()}-wide vectors"


def write_ply(path, pos, tris):
    import numpy as np

    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(pos)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(tris)}\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    faces = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<u4", 3)])
    faces["n"] = 3
    faces["i"] = tris
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(np.ascontiguousarray(pos, "<f4").tobytes())
        f.write(faces.tobytes())


# ----------------------------------------------------------------- Embree


def embree_library():
    """Compiles embree_frame.c against embreex's libembree4 (once per source
    change) and loads it with ctypes."""
    import ctypes

    import embreex

    libs = glob.glob(os.path.join(os.path.dirname(embreex.__file__), "..", "embreex.libs", "libembree4*"))
    if not libs:
        raise RuntimeError("embreex ships no libembree4 (embreex.libs/ is missing)")
    lib = os.path.realpath(libs[0])
    src = os.path.join(HERE, "embree_frame.c")
    out_dir = os.path.join(sys.prefix, "penumbra-peers")
    os.makedirs(out_dir, exist_ok=True)
    stamp = f"{os.path.getmtime(src):.0f}-{os.path.getsize(src)}"
    so = os.path.join(out_dir, f"embree_frame-{stamp}.so")
    if not os.path.exists(so):
        cc = os.environ.get("CC", "cc")
        cmd = [cc, "-O2", "-shared", "-fPIC", "-o", so, src, lib,
               f"-Wl,-rpath,{os.path.dirname(lib)}", "-lpthread", "-lm"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"compiling embree_frame.c failed: {' '.join(cmd)}\n{r.stderr}")
    return ctypes.CDLL(so), lib


class Embree:
    def __init__(self, scene, packets, threads):
        import ctypes

        import numpy as np

        self.lib, libpath = embree_library()
        self.np, self.ct = np, ctypes
        self.scene_in, self.packets, self.threads = scene, packets, threads
        pos, tris = scene.merged()
        self.pos, self.tris = np.ascontiguousarray(pos), np.ascontiguousarray(tris)
        from importlib.metadata import version

        self.lib.pe_property.restype = ctypes.c_long
        t0 = time.perf_counter()
        p = ctypes.POINTER(ctypes.c_float)
        u = ctypes.POINTER(ctypes.c_uint)
        err = self.lib.pe_init(
            self.pos.ctypes.data_as(p), len(self.pos),
            self.tris.ctypes.data_as(u), len(self.tris), threads, isa().encode(),
        )
        if err != 0:
            raise RuntimeError(f"Embree error {err} building the scene")
        self.setup_ms = (time.perf_counter() - t0) * 1e3
        v = self.lib.pe_property(0)
        self.version = (
            f"embreex {version('embreex')}, Embree {v // 10000}.{v // 100 % 100}.{v % 100}"
        )
        self.notes = "rtcIntersect1, rtcOccluded1" + ("; Embree device isa=avx2" if isa() else "")
        self.width = 0
        if packets:
            native = [w for w, prop in [(16, 34), (8, 33), (4, 32)] if self.lib.pe_property(prop)]
            if not native:
                raise RuntimeError("this Embree build runs no ray packets natively")
            self.width = native[0]
            tile = {16: "4×4", 8: "4×2", 4: "2×2"}[self.width]
            self.notes = (
                f"{self.width}-ray packets of {tile} pixels (rtcIntersect{self.width}, "
                f"rtcOccluded{self.width}): the widest this Embree build runs natively on this CPU"
                + ("" if self.width == 16 else " (16-ray packets need AVX-512 in both)")
                + ("; Embree device isa=avx2" if isa() else "")
            )
        self.cam = (ctypes.c_float * 12)(*scene.camera_vectors())
        self.to_light = (ctypes.c_float * 3)(*scene.light["to_light"])
        self.out = (ctypes.c_uint64 * 3)()

    def frame(self):
        s = self.scene_in
        err = self.lib.pe_frame(
            self.width, self.cam, self.to_light,
            s.width, s.height, self.threads, self.out,
        )
        if err != 0:
            raise RuntimeError(f"Embree error {err} in a frame")

    def counts(self):
        self.frame()
        hits, shadow_rays, blocked = (int(x) for x in self.out)
        # The same primary rays through embreex's own API (one thread).
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        es = rtcore_scene.EmbreeScene()
        TriangleMesh(es, self.pos[self.tris])
        o, d = self.scene_in.primary_rays()
        embreex_hits = int((es.run(o, d) >= 0).sum())
        if embreex_hits != hits:
            raise RuntimeError(
                f"embree_frame.c counted {hits} hits, embreex's own API {embreex_hits}"
            )
        return {"hits": hits, "shadow_rays": shadow_rays, "blocked": blocked}


# ----------------------------------------------------------------- driver


def make(peer, scene, threads):
    if peer == "mitsuba-llvm":
        return Mitsuba(scene, "llvm_ad_rgb", threads)
    if peer == "mitsuba-scalar":
        return Mitsuba(scene, "scalar_rgb", threads)
    if peer == "embree-single":
        return Embree(scene, False, threads)
    if peer == "embree-packets":
        return Embree(scene, True, threads)
    raise SystemExit(f"unknown peer {peer!r} (expected one of {', '.join(PEERS)})")


def timed(p):
    t0 = time.perf_counter()
    p.frame()
    return (time.perf_counter() - t0) * 1e3


def ready_line(peer, p, args, first_ms):
    return {
        "peer": peer,
        "version": p.version,
        "notes": p.notes,
        "threads": args.threads,
        "width": args.width,
        "height": args.height,
        "setup_ms": p.setup_ms,
        "first_frame_ms": first_ms,
        **p.counts(),
    }


def emit(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("command", choices=["run", "serve", "versions"])
    ap.add_argument("peers", nargs="*")
    ap.add_argument("--scene", default=os.path.join(ROOT, "scenes", "bunny_scene.glb"))
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=1024)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--frames", type=int, default=5)
    args = ap.parse_args()
    if args.command == "versions":
        from importlib.metadata import version

        emit({k: version(k) for k in ["mitsuba", "drjit", "embreex", "numpy"]} | {"python": sys.version.split()[0]})
        return
    scene = Scene(args.scene, args.width, args.height)
    if args.command == "serve":
        if len(args.peers) != 1:
            raise SystemExit("serve takes one peer")
        peer = args.peers[0]
        try:
            p = make(peer, scene, args.threads)
            first = timed(p)
            timed(p)  # warm-up
            emit(ready_line(peer, p, args, first))
        except Exception as e:  # reported to the benchmark, which goes on without this peer
            emit({"peer": peer, "error": f"{type(e).__name__}: {e}"})
            return
        for line in sys.stdin:
            if line.strip() == "frame":
                emit({"frame_ms": timed(p)})
            elif line.strip() == "quit":
                break
        return
    for peer in args.peers or PEERS:
        p = make(peer, scene, args.threads)
        first = timed(p)
        emit(ready_line(peer, p, args, first))
        for _ in range(args.frames):
            emit({"peer": peer, "frame_ms": timed(p)})


if __name__ == "__main__":
    main()
