/*
 * embree-memory: Embree's own memory figure for the two scenes of
 * tests/memory/huge_scene.rs and tests/memory/huge_mesh.rs (BENCHMARKS.md, "Memory at
 * the peak of a huge render"). Builds each
 * scene with Embree 3 (default device, default build quality) and counts, through the
 * device's memory monitor callback (rtcSetDeviceMemoryMonitorFunction), the bytes Embree
 * holds after its geometry buffers are filled ("stored") and at most while it commits the
 * scene ("peak"), per primitive. Only what Embree allocates is counted: its geometry
 * buffers (rtcSetNewGeometryBuffer), the BVH and the build's temporary arrays.
 *
 * The scenes are those of the tests, made the way Embree takes them:
 * - spheres: 250 x 200 x 200 of radius 0.25 one unit apart, RTC_GEOMETRY_TYPE_SPHERE_POINT
 *   (16 bytes a sphere);
 * - triangles: the tests' height field of 2500 x 2000 cells of two triangles, an indexed
 *   RTC_GEOMETRY_TYPE_TRIANGLE mesh with shared vertices (p3trace stores each triangle's
 *   own vertex and edges).
 *
 * Not part of the build or of CI. Needs Debian's libembree-dev:
 *   gcc -O2 -Wall -Wextra scripts/embree-memory.c -lembree3 -lm -o /tmp/embree-memory
 *   /tmp/embree-memory
 */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>

static atomic_llong held, peak;

/* Called with a positive count before each allocation and a negative one after each
 * release; the peak follows the count. */
static bool monitor(void *user, ssize_t bytes, bool post) {
  (void)user;
  (void)post;
  long long now = atomic_fetch_add(&held, (long long)bytes) + (long long)bytes;
  long long top = atomic_load(&peak);
  while (now > top && !atomic_compare_exchange_weak(&peak, &top, now)) {
  }
  return true;
}

static void error(void *user, enum RTCError code, const char *what) {
  (void)user;
  fprintf(stderr, "embree error %d: %s\n", (int)code, what);
  exit(1);
}

/* The tests' landscape (tests/memory/huge_mesh.rs). */
static float height(unsigned x, unsigned y) {
  float fx = (float)x, fy = (float)y;
  return 2.0f * sinf(fx * 0.013f) * cosf(fy * 0.017f) + 0.5f * sinf(fx * 0.11f + fy * 0.07f);
}

static RTCGeometry spheres(RTCDevice dev, size_t *count) {
  const unsigned sides[3] = {250, 200, 200};
  *count = (size_t)sides[0] * sides[1] * sides[2];
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
  float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                     4 * sizeof(float), *count);
  for (unsigned x = 0; x < sides[0]; x++)
    for (unsigned y = 0; y < sides[1]; y++)
      for (unsigned z = 0; z < sides[2]; z++) {
        v[0] = (float)x, v[1] = (float)y, v[2] = (float)z, v[3] = 0.25f;
        v += 4;
      }
  return g;
}

static RTCGeometry triangles(RTCDevice dev, size_t *count) {
  const unsigned cells[2] = {2500, 2000}, row = cells[1] + 1;
  *count = 2 * (size_t)cells[0] * cells[1];
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                     3 * sizeof(float), (size_t)(cells[0] + 1) * row);
  unsigned *t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                        3 * sizeof(unsigned), *count);
  for (unsigned x = 0; x <= cells[0]; x++)
    for (unsigned y = 0; y <= cells[1]; y++) {
      v[0] = (float)x, v[1] = (float)y, v[2] = height(x, y);
      v += 3;
    }
  /* Cell (x, y) as the test splits it: (a, b, c) and (a, c, d). */
  for (unsigned x = 0; x < cells[0]; x++)
    for (unsigned y = 0; y < cells[1]; y++) {
      unsigned a = x * row + y, b = a + row, c = b + 1, d = a + 1;
      t[0] = a, t[1] = b, t[2] = c, t[3] = a, t[4] = c, t[5] = d;
      t += 6;
    }
  return g;
}

/* Each scene on a device of its own, so that nothing of the other is counted. */
static void measure(const char *name, const char *kind, RTCGeometry (*make)(RTCDevice, size_t *)) {
  RTCDevice dev = rtcNewDevice(NULL);
  if (!dev) {
    fprintf(stderr, "rtcNewDevice failed\n");
    exit(1);
  }
  rtcSetDeviceErrorFunction(dev, error, NULL);
  atomic_store(&held, 0);
  atomic_store(&peak, 0);
  rtcSetDeviceMemoryMonitorFunction(dev, monitor, NULL);
  RTCScene scene = rtcNewScene(dev);
  size_t count;
  RTCGeometry g = make(dev, &count);
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  long long stored = atomic_load(&held);
  rtcCommitScene(scene);
  long long top = atomic_load(&peak), after = atomic_load(&held);
  printf("%s: stored %.1f bytes per %s; peak of the build %.1f (%.2f GB); held after it %.1f\n",
         name, (double)stored / count, kind, (double)top / count, top / 1e9,
         (double)after / count);
  rtcReleaseScene(scene);
  rtcReleaseDevice(dev);
}

int main(void) {
  printf("embree %d.%d.%d\n", RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH);
  measure("10M spheres", "sphere", spheres);
  measure("10M triangles", "triangle", triangles);
  return 0;
}
