/* Embree 4 ray queries for the benchmark's peer figures (tools/measure/peers/peers.py).
 *
 * One "frame" is the benchmark scene's ray work without shading: a primary
 * ray through every pixel centre (penumbra's camera model), and for every hit
 * whose normal (turned towards the viewer) faces the light, one shadow ray
 * towards the directional light. The rays are traced either one at a time
 * (rtcIntersect1 / rtcOccluded1) or as packets of 4, 8 or 16 neighbouring
 * pixels (rtcIntersect4/8/16, rtcOccluded4/8/16), on `threads` POSIX threads
 * that take rows of 4x4-pixel tiles from a shared counter.
 *
 * Built by peers.py with the system C compiler against the libembree4 that
 * the PyPI package embreex ships (it exposes only Embree's single-ray calls to
 * Python, and a Python loop over packets would time Python instead of Embree).
 * Embree's headers are not in that wheel, so the few declarations needed are
 * written out below from Embree 4's public API (rtcore_ray.h and friends). */

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *RTCDevice;
typedef void *RTCScene;
typedef void *RTCGeometry;

enum { RTC_GEOMETRY_TYPE_TRIANGLE = 0 };
enum { RTC_BUFFER_TYPE_INDEX = 0, RTC_BUFFER_TYPE_VERTEX = 1 };
enum { RTC_FORMAT_UINT3 = 0x5003, RTC_FORMAT_FLOAT3 = 0x9003 };
#define RTC_INVALID_GEOMETRY_ID ((unsigned)-1)

RTCDevice rtcNewDevice(const char *config);
int rtcGetDeviceError(RTCDevice device);
RTCScene rtcNewScene(RTCDevice device);
RTCGeometry rtcNewGeometry(RTCDevice device, int type);
void *rtcSetNewGeometryBuffer(RTCGeometry g, int type, unsigned slot, int format,
                              size_t byte_stride, size_t item_count);
void rtcCommitGeometry(RTCGeometry g);
unsigned rtcAttachGeometry(RTCScene s, RTCGeometry g);
void rtcReleaseGeometry(RTCGeometry g);
void rtcCommitScene(RTCScene s);
void rtcIntersect1(RTCScene s, void *rayhit, void *args);
void rtcOccluded1(RTCScene s, void *ray, void *args);
void rtcIntersect16(const int *valid, RTCScene s, void *rayhit, void *args);
void rtcOccluded16(const int *valid, RTCScene s, void *ray, void *args);

/* RTCRay, then RTCHit up to geomID. The instance fields after geomID are
 * written by Embree but never read here: the struct leaves room for them. */
struct ray1 {
  float org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z, time, tfar;
  unsigned mask, id, flags;
};
struct rayhit1 {
  struct ray1 ray;
  float ng_x, ng_y, ng_z, u, v;
  unsigned prim_id, geom_id;
  unsigned pad[9];
} __attribute__((aligned(16)));
static RTCDevice device;
static RTCScene scene;
static float *tri_normal; /* unnormalised geometric normal per triangle */

/* Builds the scene from `nt` triangles (`idx`, 3 per triangle) over `nv`
 * vertices (`pos`, xyz) on a device of `threads` threads that uses the
 * instruction set `isa` (Embree's device configuration, e.g. "avx2"), or the
 * best the CPU has when `isa` is empty. Returns 0, or Embree's error code. */
int pe_init(const float *pos, unsigned nv, const unsigned *idx, unsigned nt,
            int threads, const char *isa) {
  char config[96];
  snprintf(config, sizeof config, "threads=%d%s%s", threads, *isa ? ",isa=" : "", isa);
  device = rtcNewDevice(config);
  if (!device) return -1;
  scene = rtcNewScene(device);
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                     RTC_FORMAT_FLOAT3, 12, nv);
  unsigned *t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0,
                                        RTC_FORMAT_UINT3, 12, nt);
  if (!v || !t) return rtcGetDeviceError(device);
  memcpy(v, pos, 12 * (size_t)nv);
  memcpy(t, idx, 12 * (size_t)nt);
  tri_normal = malloc(12 * (size_t)nt);
  for (unsigned i = 0; i < nt; i++) {
    const float *a = pos + 3 * idx[3 * i], *b = pos + 3 * idx[3 * i + 1],
                *c = pos + 3 * idx[3 * i + 2];
    float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    tri_normal[3 * i] = e1[1] * e2[2] - e1[2] * e2[1];
    tri_normal[3 * i + 1] = e1[2] * e2[0] - e1[0] * e2[2];
    tri_normal[3 * i + 2] = e1[0] * e2[1] - e1[1] * e2[0];
  }
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(scene);
  return rtcGetDeviceError(device);
}

struct job {
  int packets, width, height;
  float eye[3], fwd[3], right[3], up[3], to_light[3];
  int next_row; /* next row of 4x4 tiles, taken atomically */
};
struct counts {
  uint64_t hits, shadow_rays, blocked;
};

static void primary(const struct job *j, int x, int y, float d[3]) {
  float nx = ((float)x + 0.5f) / (float)j->width * 2.0f - 1.0f;
  float ny = 1.0f - ((float)y + 0.5f) / (float)j->height * 2.0f;
  float len = 0.0f;
  for (int k = 0; k < 3; k++) {
    d[k] = j->fwd[k] + nx * j->right[k] + ny * j->up[k];
    len += d[k] * d[k];
  }
  len = sqrtf(len);
  for (int k = 0; k < 3; k++) d[k] /= len;
}

/* The shadow ray of a hit at distance t along d on triangle prim: origin on
 * the surface, a small offset along the normal facing the viewer; returns 0
 * when that normal faces away from the light (no shadow ray). */
static int shadow(const struct job *j, const float d[3], float t, unsigned prim,
                  float org[3]) {
  const float *n = tri_normal + 3 * prim;
  float nd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
  float s = nd > 0.0f ? -1.0f : 1.0f;
  float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  float nl = s * (n[0] * j->to_light[0] + n[1] * j->to_light[1] +
                  n[2] * j->to_light[2]);
  if (!(nl > 0.0f)) return 0;
  float scale = 0.0f;
  for (int k = 0; k < 3; k++) {
    org[k] = j->eye[k] + t * d[k];
    scale = fmaxf(scale, fabsf(org[k]));
  }
  float eps = 1e-4f * (1.0f + scale);
  for (int k = 0; k < 3; k++) org[k] += s * n[k] / len * eps;
  return 1;
}

static void tile_row_single(struct job *j, int ty, struct counts *c) {
  for (int y = ty * 4; y < ty * 4 + 4 && y < j->height; y++)
    for (int x = 0; x < j->width; x++) {
      float d[3], org[3];
      primary(j, x, y, d);
      struct rayhit1 rh = {{j->eye[0], j->eye[1], j->eye[2], 0.0f, d[0], d[1],
                            d[2], 0.0f, INFINITY, ~0u, 0, 0}};
      rh.geom_id = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &rh, NULL);
      if (rh.geom_id == RTC_INVALID_GEOMETRY_ID) continue;
      c->hits++;
      if (!shadow(j, d, rh.ray.tfar, rh.prim_id, org)) continue;
      c->shadow_rays++;
      struct ray1 r = {org[0],         org[1],         org[2],  0.0f,
                       j->to_light[0], j->to_light[1], j->to_light[2],
                       0.0f,           INFINITY,       ~0u,     0, 0};
      rtcOccluded1(scene, &r, NULL);
      c->blocked += r.tfar < 0.0f;
    }
}

/* A packet of `width` (4, 8 or 16) rays as Embree lays out RTCRayHitN:
 * each field an array of `width` values, the ray's 12 fields first, then the
 * hit's (Ng x, y, z, u, v, primID, geomID, instance fields). */
enum { F_ORG = 0, F_TNEAR = 3, F_DIR = 4, F_TIME = 7, F_TFAR = 8, F_MASK = 9,
       F_ID = 10, F_FLAGS = 11, F_PRIM = 17, F_GEOM = 18, F_FIELDS = 32 };
typedef void (*intersect_n)(const int *, RTCScene, void *, void *);
void rtcIntersect4(const int *valid, RTCScene s, void *rayhit, void *args);
void rtcOccluded4(const int *valid, RTCScene s, void *ray, void *args);
void rtcIntersect8(const int *valid, RTCScene s, void *rayhit, void *args);
void rtcOccluded8(const int *valid, RTCScene s, void *ray, void *args);

static void set_ray(float *p, int width, int i, const float org[3],
                    const float dir[3]) {
  unsigned *u = (unsigned *)p;
  for (int k = 0; k < 3; k++) {
    p[(F_ORG + k) * width + i] = org[k];
    p[(F_DIR + k) * width + i] = dir[k];
  }
  p[F_TNEAR * width + i] = 0.0f;
  p[F_TIME * width + i] = 0.0f;
  p[F_TFAR * width + i] = INFINITY;
  u[F_MASK * width + i] = ~0u;
  u[F_ID * width + i] = i;
  u[F_FLAGS * width + i] = 0;
  u[F_GEOM * width + i] = RTC_INVALID_GEOMETRY_ID;
}

/* Packets of 4x4 pixels (width 16), 4x2 (8) or 2x2 (4). */
static void tile_row_packets(struct job *j, int ty, struct counts *c) {
  int width = j->packets, tw = width == 4 ? 2 : 4, th = width / tw;
  intersect_n isect = width == 16 ? rtcIntersect16 : width == 8 ? rtcIntersect8 : rtcIntersect4;
  intersect_n occl = width == 16 ? rtcOccluded16 : width == 8 ? rtcOccluded8 : rtcOccluded4;
  float rh[F_FIELDS * 16] __attribute__((aligned(64)));
  float sr[F_FIELDS * 16] __attribute__((aligned(64)));
  unsigned *geom = (unsigned *)rh + F_GEOM * width, *prim = (unsigned *)rh + F_PRIM * width;
  int valid[16] __attribute__((aligned(64))), svalid[16] __attribute__((aligned(64)));
  float dirs[16][3];
  for (int band = 0; band < 4 / th; band++)
    for (int tx = 0; tx < (j->width + tw - 1) / tw; tx++) {
      for (int i = 0; i < width; i++) {
        int x = tx * tw + i % tw, y = ty * 4 + band * th + i / tw;
        valid[i] = (x < j->width && y < j->height) ? -1 : 0;
        if (!valid[i]) continue;
        primary(j, x, y, dirs[i]);
        set_ray(rh, width, i, j->eye, dirs[i]);
      }
      isect(valid, scene, rh, NULL);
      int any = 0;
      for (int i = 0; i < width; i++) {
        svalid[i] = 0;
        if (!valid[i] || geom[i] == RTC_INVALID_GEOMETRY_ID) continue;
        c->hits++;
        float org[3];
        if (!shadow(j, dirs[i], rh[F_TFAR * width + i], prim[i], org)) continue;
        svalid[i] = -1;
        any = 1;
        c->shadow_rays++;
        set_ray(sr, width, i, org, j->to_light);
      }
      if (!any) continue;
      occl(svalid, scene, sr, NULL);
      for (int i = 0; i < width; i++) c->blocked += svalid[i] && sr[F_TFAR * width + i] < 0.0f;
    }
}

/* Embree's rtcGetDeviceProperty: 0 the version (e.g. 40400), 32, 33, 34
 * whether 4-, 8- and 16-ray packets run natively on this CPU (rtcIntersect16
 * is called only where 34 says so). */
long rtcGetDeviceProperty(RTCDevice device, int prop);
long pe_property(int prop) { return rtcGetDeviceProperty(device, prop); }

struct worker {
  struct job *job;
  struct counts counts;
};

static void *work(void *arg) {
  struct worker *w = arg;
  struct job *j = w->job;
  int rows = (j->height + 3) / 4;
  for (;;) {
    int ty = __atomic_fetch_add(&j->next_row, 1, __ATOMIC_RELAXED);
    if (ty >= rows) break;
    if (j->packets)
      tile_row_packets(j, ty, &w->counts);
    else
      tile_row_single(j, ty, &w->counts);
  }
  return NULL;
}

/* One frame, `packets` = 0 (one ray at a time) or the packet width (4, 8,
 * 16): cam = eye, forward, right and up (the last two scaled by the
 * image plane's half extents at distance 1), to_light = unit vector towards
 * the light. Writes hits, shadow rays and blocked shadow rays to out. */
int pe_frame(int packets, const float cam[12], const float to_light[3],
             int width, int height, int threads, uint64_t out[3]) {
  struct job j = {packets, width, height};
  memcpy(j.eye, cam, 12);
  memcpy(j.fwd, cam + 3, 12);
  memcpy(j.right, cam + 6, 12);
  memcpy(j.up, cam + 9, 12);
  memcpy(j.to_light, to_light, 12);
  if (threads < 1) threads = 1;
  if (threads > 64) threads = 64;
  pthread_t tid[64];
  struct worker w[64];
  for (int i = 0; i < threads; i++) {
    w[i] = (struct worker){&j, {0, 0, 0}};
    if (i > 0) pthread_create(&tid[i], NULL, work, &w[i]);
  }
  work(&w[0]);
  out[0] = out[1] = out[2] = 0;
  for (int i = 0; i < threads; i++) {
    if (i > 0) pthread_join(tid[i], NULL);
    out[0] += w[i].counts.hits;
    out[1] += w[i].counts.shadow_rays;
    out[2] += w[i].counts.blocked;
  }
  return rtcGetDeviceError(device);
}
