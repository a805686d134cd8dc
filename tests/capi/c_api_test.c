/* The C API (client/c/include/dn/dn.h) from C99, against a real dnserver
 * whose URL is argv[1] (tests/capi/capi_test.cpp starts the server).
 * Prints every failed check and exits 1 if there was one. */
#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv, nanosleep */

#include <dn/dn.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char* g_url;
static int g_checks, g_failures;

#define CHECK(cond, ...)                                                             \
  do {                                                                               \
    ++g_checks;                                                                      \
    if (!(cond)) {                                                                   \
      ++g_failures;                                                                  \
      fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond);       \
      fprintf(stderr, __VA_ARGS__);                                                  \
      fputc('\n', stderr);                                                           \
    }                                                                                \
  } while (0)

/* The device's error must be `code` with a message containing `needle`. */
static void expect_error_at(int line, DNDevice dev, DNError code, const char* needle) {
  const char* message = NULL;
  const DNError got = dnGetDeviceError(dev, &message);
  ++g_checks;
  if (got != code || !message || !strstr(message, needle)) {
    ++g_failures;
    fprintf(stderr, "%s:%d: expected error %d naming \"%s\", got %d: %s\n", __FILE__, line, (int)code, needle,
            (int)got, message ? message : "(null)");
  } else {
    printf("  expected error %d: %s\n", (int)got, message);
  }
}
#define EXPECT_ERROR(dev, code, needle) expect_error_at(__LINE__, dev, code, needle)

static void expect_ok_at(int line, DNDevice dev, const char* what) {
  const char* message = NULL;
  const DNError got = dnGetDeviceError(dev, &message);
  ++g_checks;
  if (got != DN_ERROR_NONE) {
    ++g_failures;
    fprintf(stderr, "%s:%d: %s: unexpected error %d: %s\n", __FILE__, line, what, (int)got, message);
  }
}
#define EXPECT_OK(dev, what) expect_ok_at(__LINE__, dev, what)

static DNDevice connected_device(void) {
  DNDevice dev = dnNewDevice(g_url);
  dnSetDevice1s(dev, "client_name", "c_api_test");
  dnCommitDevice(dev);
  EXPECT_OK(dev, "connect");
  return dev;
}

/* A repeatable pseudo-random value in [0, 1). */
static float noise(unsigned* state) {
  *state = *state * 1664525u + 1013904223u;
  return (float)(*state >> 8) / 16777216.0f;
}

enum { W = 24, H = 10 };

/* A committed passthrough filter from `color` to `out`, packed W x H FLOAT3. */
static DNFilter passthrough_filter(DNDevice dev, float* color, float* out) {
  DNFilter f = dnNewFilter(dev, "passthrough");
  dnSetSharedFilterImage(f, "color", color, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "output", out, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnCommitFilter(f);
  return f;
}

static void test_passthrough_packed(void) {
  printf("passthrough, packed FLOAT3\n");
  DNDevice dev = connected_device();
  DNFilter f = dnNewFilter(dev, "passthrough");
  static float color[W * H * 3], out[W * H * 3];
  unsigned s = 1;
  for (int i = 0; i < W * H * 3; ++i) color[i] = noise(&s) * 100.0f + (i % 7 == 0 ? 1e4f : 0.0f);
  color[0] = 1e-6f;
  dnSetSharedFilterImage(f, "color", color, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "output", out, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnCommitFilter(f);
  EXPECT_OK(dev, "commit");
  dnExecuteFilter(f);
  EXPECT_OK(dev, "execute");
  CHECK(memcmp(color, out, sizeof color) == 0, "passthrough output differs from the colour");

  /* The watch hint: session id, key and the whole command. */
  const uint64_t id = dnGetFilterSessionId(f);
  const char* key = dnGetFilterWatchKey(f);
  const char* cmd = dnGetFilterWatchCommand(f);
  EXPECT_OK(dev, "watch getters");
  CHECK(id != 0, "session id 0");
  CHECK(key && strlen(key) == 32, "watch key '%s'", key ? key : "(null)");
  /* The key goes to dn's environment, never its command line. */
  CHECK(cmd && strncmp(cmd, "DN_WATCH_KEY=", 13) == 0 && strncmp(cmd + 13, key, 32) == 0 &&
            strncmp(cmd + 45, " dn watch --server ", 19) == 0 && !strstr(cmd, "--key"),
        "watch command '%s'", cmd ? cmd : "(null)");
  printf("  %s\n", cmd ? cmd : "(null)");

  /* The same images again: no new session (the history stays). */
  dnCommitFilter(f);
  EXPECT_OK(dev, "second commit");
  CHECK(dnGetFilterSessionId(f) == id, "an unchanged commit opened a new session");

  /* Sharing the input with watchers (protocol 1.7) describes another session. */
  dnSetFilter1b(f, "share_input", true);
  CHECK(dnGetFilter1i(f, "share_input") == 1, "share_input reads back as %d", dnGetFilter1i(f, "share_input"));
  dnCommitFilter(f);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "share_input");
  CHECK(dnGetFilterSessionId(f) != id, "share_input kept the session opened without it");
  CHECK(memcmp(color, out, sizeof color) == 0, "passthrough output differs with share_input");

  /* HALF3 in and out: the half bits come back. */
  static uint16_t hcolor[W * H * 3], hout[W * H * 3];
  for (int i = 0; i < W * H * 3; ++i) hcolor[i] = (uint16_t)(0x3c00 + (i * 37) % 0x0800); /* [1, 4) */
  dnSetSharedFilterImage(f, "color", hcolor, DN_FORMAT_HALF3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "output", hout, DN_FORMAT_HALF3, W, H, 0, 0, 0);
  dnCommitFilter(f);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "half execute");
  CHECK(dnGetFilterSessionId(f) != id, "a change of format kept the session");
  CHECK(memcmp(hcolor, hout, sizeof hcolor) == 0, "HALF3 passthrough output differs");

  dnReleaseFilter(f);
  dnReleaseDevice(dev);
}

/* "auto": colour, albedo and normal of one frame (oidnNewFilter(dev, "RT")'s
 * inputs) denoised by the pipeline the server chooses, named with its reason. */
static void test_auto(void) {
  printf("auto, colour + albedo + normal\n");
  DNDevice dev = connected_device();
  DNFilter f = dnNewFilter(dev, "auto");
  EXPECT_OK(dev, "new auto filter");
  static float color[W * H * 3], albedo[W * H * 3], normal[W * H * 3], out[W * H * 3];
  unsigned s = 7;
  for (int i = 0; i < W * H * 3; ++i) {
    color[i] = 0.5f + noise(&s) * 0.1f;
    albedo[i] = 0.5f;
    normal[i] = (i % 3 == 2) ? 1.0f : 0.0f;
  }
  dnSetSharedFilterImage(f, "color", color, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "albedo", albedo, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "normal", normal, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "output", out, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnCommitFilter(f);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "auto execute");
  const char* pipeline = dnGetFilterPipeline(f);
  const char* reason = dnGetFilterPipelineReason(f);
  CHECK(pipeline && strcmp(pipeline, "image") == 0, "auto chose '%s' for colour, albedo and normal",
        pipeline ? pipeline : "(null)");
  CHECK(reason && strlen(reason) > 0, "no reason for the choice");
  printf("  %s: %s\n", pipeline ? pipeline : "(null)", reason ? reason : "(null)");
  /* Flat albedo and normal, noise of 0.1 around 0.55: the output is closer to the mean than the input. */
  double in_err = 0, out_err = 0;
  for (int i = 0; i < W * H * 3; ++i) {
    in_err += (color[i] - 0.55) * (color[i] - 0.55);
    out_err += (out[i] - 0.55) * (out[i] - 0.55);
  }
  CHECK(out_err < in_err, "auto output error %g not below the input's %g", out_err, in_err);
  dnReleaseFilter(f);
  dnReleaseDevice(dev);
}

static void test_passthrough_strided(void) {
  printf("passthrough, interleaved RGBA with padded rows\n");
  DNDevice dev = connected_device();
  DNFilter f = dnNewFilter(dev, "passthrough");
  enum { kPad = 40, kRow = W * 16 + kPad, kOffset = 8 };
  static unsigned char in[kOffset + H * kRow], out[kOffset + H * kRow];
  static float expected[W * H * 3];
  unsigned s = 7;
  memset(in, 0xAB, sizeof in);
  memset(out, 0xCD, sizeof out);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int c = 0; c < 4; ++c) {
        const float v = c == 3 ? -1.0f : noise(&s) * 10.0f;
        memcpy(in + kOffset + y * kRow + x * 16 + c * 4, &v, 4);
        if (c < 3) expected[(y * W + x) * 3 + c] = v;
      }
  dnSetSharedFilterImage(f, "color", in, DN_FORMAT_FLOAT3, W, H, kOffset, 16, kRow);
  dnSetSharedFilterImage(f, "output", out, DN_FORMAT_FLOAT3, W, H, kOffset, 16, kRow);
  dnCommitFilter(f);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "strided execute");
  int wrong = 0, touched = 0;
  for (int i = 0; i < kOffset; ++i) touched += out[i] != 0xCD;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const unsigned char* p = out + kOffset + y * kRow + x * 16;
      for (int c = 0; c < 3; ++c) {
        float v;
        memcpy(&v, p + c * 4, 4);
        wrong += v != expected[(y * W + x) * 3 + c];
      }
      for (int b = 12; b < 16; ++b) touched += p[b] != 0xCD; /* alpha left alone */
    }
    for (int b = W * 16; b < kRow; ++b) touched += out[kOffset + y * kRow + b] != 0xCD; /* row padding */
  }
  CHECK(wrong == 0, "%d strided output components differ from the colour", wrong);
  CHECK(touched == 0, "%d bytes outside the output's pixels were written", touched);

  /* Pointers and strides change without a new commit; the session stays. */
  const uint64_t id = dnGetFilterSessionId(f);
  static float packed[W * H * 3];
  dnSetSharedFilterImage(f, "output", packed, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "execute into a packed output without a commit");
  CHECK(memcmp(packed, expected, sizeof packed) == 0, "packed output differs");
  CHECK(dnGetFilterSessionId(f) == id, "a pointer change opened a new session");
  dnReleaseFilter(f);
  dnReleaseDevice(dev);
}

/* accumulate with alpha_min 0 and max_history >= the frame count is the
 * running mean of the frames (docs/pipelines.md, "accumulate in detail"). */
enum { kFrames = 6 };
static float g_colors[kFrames + 2][W * H * 3];

static void check_mean(const float* out, int first, int last, const char* what) {
  double worst = 0.0;
  for (int i = 0; i < W * H * 3; ++i) {
    double mean = 0.0;
    for (int k = first; k <= last; ++k) mean += g_colors[k][i];
    mean /= (double)(last - first + 1);
    const double rel = fabs(out[i] - mean) / (fabs(mean) + 1e-6);
    if (rel > worst) worst = rel;
  }
  CHECK(worst < 1e-5, "%s: output is not the mean of frames %d..%d (worst relative error %g)", what, first, last,
        worst);
}

static void test_accumulate(int async) {
  printf("accumulate, %s\n", async ? "dnExecuteFilterAsync + dnSyncFilter" : "dnExecuteFilter");
  DNDevice dev = connected_device();
  DNFilter f = dnNewFilter(dev, "accumulate");
  static float color[W * H * 3], normal[W * H * 3], depth[W * H], motion[W * H * 2], outs[kFrames + 2][W * H * 3];
  for (int i = 0; i < W * H; ++i) {
    normal[3 * i + 0] = 0.0f;
    normal[3 * i + 1] = 0.0f;
    normal[3 * i + 2] = 1.0f;
    depth[i] = 2.0f;
    motion[2 * i] = motion[2 * i + 1] = 0.0f;
  }
  unsigned s = 99;
  for (int k = 0; k < kFrames + 2; ++k)
    for (int i = 0; i < W * H * 3; ++i) g_colors[k][i] = 0.5f + noise(&s) * (i % 2 ? 4.0f : 0.25f);

  dnSetSharedFilterImage(f, "color", color, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "normal", normal, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "depth", depth, DN_FORMAT_FLOAT, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "motion", motion, DN_FORMAT_FLOAT2, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "output", outs[0], DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetFilter1f(f, "alpha_min", 0.0f);
  dnSetFilter1i(f, "max_history", 64);
  dnSetFilter1b(f, "hdr", true);
  dnSetFilter1i(f, "motion_convention", DN_MOTION_PIXELS_TO_PREVIOUS);
  EXPECT_OK(dev, "set");
  CHECK(dnGetFilter1f(f, "alpha_min") == 0.0f, "alpha_min reads %g", dnGetFilter1f(f, "alpha_min"));
  CHECK(dnGetFilter1i(f, "max_history") == 64, "max_history reads %d", dnGetFilter1i(f, "max_history"));
  CHECK(fabsf(dnGetFilter1f(f, "depth_tolerance") - 0.1f) < 1e-7f, "depth_tolerance default reads %g",
        dnGetFilter1f(f, "depth_tolerance"));
  dnCommitFilter(f);
  EXPECT_OK(dev, "commit");

  /* A still camera, set once. */
  const float view[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -3, 1};
  const float projection[16] = {1.2f, 0, 0, 0, 0, 2.4f, 0, 0, 0, 0, -1.002f, -1, 0, 0, -0.2f, 0};
  const float jitter[2] = {0.0f, 0.0f};
  dnSetFilterCamera(f, view, projection, jitter);

  for (int k = 0; k < kFrames; ++k) {
    memcpy(color, g_colors[k], sizeof color); /* the renderer's buffer, rewritten every frame */
    dnSetSharedFilterImage(f, "output", outs[k], DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
    if (async) dnExecuteFilterAsync(f);
    else dnExecuteFilter(f);
  }
  if (async) dnSyncFilter(f);
  EXPECT_OK(dev, "frames");
  for (int k = 0; k < kFrames; ++k) {
    char what[64];
    snprintf(what, sizeof what, "frame %d", k);
    check_mean(outs[k], 0, k, what);
  }

  /* dnResetFilterHistory: the next frame is its own colour, the one after the mean of two. */
  dnResetFilterHistory(f);
  for (int k = kFrames; k < kFrames + 2; ++k) {
    memcpy(color, g_colors[k], sizeof color);
    dnSetSharedFilterImage(f, "output", outs[k], DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
    if (async) dnExecuteFilterAsync(f);
    else dnExecuteFilter(f);
  }
  dnSyncFilter(f);
  EXPECT_OK(dev, "frames after the reset");
  check_mean(outs[kFrames], kFrames, kFrames, "first frame after dnResetFilterHistory");
  check_mean(outs[kFrames + 1], kFrames, kFrames + 1, "second frame after dnResetFilterHistory");
  dnReleaseFilter(f);
  dnReleaseDevice(dev);
}

static int g_callback_calls;
static DNError g_callback_last;
static void on_error(void* user, DNError code, const char* message) {
  ++*(int*)user;
  g_callback_last = code;
  (void)message;
}

static void test_errors(void) {
  printf("errors\n");
  static float color[W * H * 3], out[W * H * 3], depth[W * H];

  /* A wrong server address: refused, and malformed. */
  DNDevice bad = dnNewDevice("tcp://127.0.0.1:1");
  dnCommitDevice(bad);
  EXPECT_ERROR(bad, DN_ERROR_CONNECTION, "tcp://127.0.0.1:1");
  CHECK(dnNewFilter(bad, "passthrough") == NULL, "a filter on a device that did not connect");
  EXPECT_ERROR(bad, DN_ERROR_INVALID_OPERATION, "dnCommitDevice");
  dnReleaseDevice(bad);
  bad = dnNewDevice("http://localhost:7878");
  EXPECT_ERROR(bad, DN_ERROR_INVALID_ARGUMENT, "http://localhost:7878");
  dnCommitDevice(bad);
  EXPECT_ERROR(bad, DN_ERROR_INVALID_ARGUMENT, "http://localhost:7878");
  dnReleaseDevice(bad);

  DNDevice dev = connected_device();
  g_callback_calls = 0;
  dnSetDeviceErrorFunction(dev, on_error, &g_callback_calls);

  /* An unknown pipeline. */
  CHECK(dnNewFilter(dev, "no-such-pipeline") == NULL, "a filter of an unknown pipeline");
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'no-such-pipeline'");
  CHECK(g_callback_calls == 1 && g_callback_last == DN_ERROR_INVALID_ARGUMENT, "error function called %d times",
        g_callback_calls);

  DNFilter f = dnNewFilter(dev, "accumulate");
  EXPECT_OK(dev, "new accumulate");

  /* Execute before commit. */
  dnExecuteFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_OPERATION, "dnCommitFilter");

  /* An unknown image name, a format of the wrong size, a NULL pointer. */
  dnSetSharedFilterImage(f, "colour", color, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'colour'");
  dnSetSharedFilterImage(f, "depth", depth, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'depth'");
  dnSetSharedFilterImage(f, "albedo", NULL, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'albedo'");
  dnSetSharedFilterImage(f, "color", color, DN_FORMAT_FLOAT3, W, H, 0, 8, 0);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "bytePixelStride");

  /* An unknown parameter, and one out of its range. */
  dnSetFilter1f(f, "alpha", 0.1f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'alpha'");
  dnSetFilter1i(f, "max_history", 0);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'max_history'");
  dnSetFilter1b(f, "hdr", false);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'hdr'");

  /* Sticky: the first unqueried error is kept, later ones only reach the callback. */
  g_callback_calls = 0;
  dnSetFilter1f(f, "first_unknown", 1.0f);
  dnSetFilter1f(f, "second_unknown", 1.0f);
  CHECK(g_callback_calls == 2, "error function called %d times for two errors", g_callback_calls);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'first_unknown'");
  EXPECT_OK(dev, "an error is cleared by its query");

  /* A missing required image: accumulate takes color, normal, depth, motion. */
  static float normal[W * H * 3], motion[W * H * 2];
  dnSetSharedFilterImage(f, "color", color, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "depth", depth, DN_FORMAT_FLOAT, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "motion", motion, DN_FORMAT_FLOAT2, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "output", out, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  EXPECT_OK(dev, "images");
  dnCommitFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'normal'");
  dnExecuteFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_OPERATION, "no session");

  /* An image the pipeline does not take; images of two sizes. */
  dnSetSharedFilterImage(f, "normal", normal, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetSharedFilterImage(f, "albedo", normal, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnCommitFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'albedo'");
  dnUnsetFilterImage(f, "albedo");
  dnSetSharedFilterImage(f, "depth", depth, DN_FORMAT_FLOAT, W / 2, H, 0, 0, 0);
  dnCommitFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'depth'");
  dnSetSharedFilterImage(f, "depth", depth, DN_FORMAT_FLOAT, W, H, 0, 0, 0);

  /* Now complete: it commits and runs. */
  for (int i = 0; i < W * H; ++i) {
    normal[3 * i + 2] = 1.0f;
    depth[i] = 1.0f;
    color[3 * i] = color[3 * i + 1] = color[3 * i + 2] = 0.25f;
  }
  dnCommitFilter(f);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "the filter after its errors");
  CHECK(out[0] == 0.25f, "first frame's output %g", out[0]);

  /* A change that needs a commit, without one. */
  dnSetSharedFilterImage(f, "output", out, DN_FORMAT_FLOAT3, W / 2, H, 0, 0, 0);
  dnExecuteFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_OPERATION, "dnCommitFilter");
  dnSetSharedFilterImage(f, "output", out, DN_FORMAT_FLOAT3, W, H, 0, 0, 0);
  dnSetFilter1f(f, "alpha_min", 0.5f);
  dnExecuteFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_OPERATION, "dnCommitFilter");
  dnCommitFilter(f);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "after committing the change");

  /* The device stays usable after the filter's errors: another filter works. */
  static float pout[W * H * 3];
  DNFilter p = passthrough_filter(dev, color, pout);
  dnExecuteFilter(p);
  EXPECT_OK(dev, "a second filter on the device");
  CHECK(memcmp(pout, color, sizeof pout) == 0, "second filter's output");
  dnSyncDevice(dev);
  EXPECT_OK(dev, "dnSyncDevice");

  /* Settings after commit, unknown settings and properties. */
  dnSetDevice1s(dev, "token", "x");
  EXPECT_ERROR(dev, DN_ERROR_INVALID_OPERATION, "'token'");
  CHECK(dnGetDevice1s(dev, "colour") == NULL, "an unknown property");
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'colour'");
  const char* pipelines = dnGetDevice1s(dev, "pipelines");
  CHECK(pipelines && strstr(pipelines, "accumulate") && strstr(pipelines, "svgf"), "pipelines '%s'",
        pipelines ? pipelines : "(null)");
  CHECK(dnGetDevice1i(dev, "version_major") == 1 && dnGetDevice1i(dev, "version_minor") >= 6, "version %d.%d",
        dnGetDevice1i(dev, "version_major"), dnGetDevice1i(dev, "version_minor"));
  EXPECT_OK(dev, "properties");

  /* NULL handles: this thread's error slot. */
  dnCommitDevice(NULL);
  EXPECT_ERROR(NULL, DN_ERROR_INVALID_ARGUMENT, "NULL");
  dnExecuteFilter(NULL);
  EXPECT_ERROR(NULL, DN_ERROR_INVALID_ARGUMENT, "NULL");

  dnReleaseFilter(p);
  dnReleaseFilter(f);
  dnReleaseDevice(dev);
}

static void test_default_address(void) {
  printf("default address\n");
  unsetenv("DN_SERVER");
  DNDevice dev = dnNewDevice(NULL);
  const char* url = dnGetDevice1s(dev, "url");
  CHECK(url && strcmp(url, "tcp://127.0.0.1:7878") == 0, "default url '%s'", url ? url : "(null)");
  EXPECT_OK(dev, "default url");
  dnReleaseDevice(dev);

  setenv("DN_SERVER", g_url, 1);
  dev = dnNewDevice(NULL);
  dnCommitDevice(dev);
  EXPECT_OK(dev, "connect to $DN_SERVER");
  url = dnGetDevice1s(dev, "url");
  CHECK(url && strcmp(url, g_url) == 0, "url '%s', $DN_SERVER '%s'", url ? url : "(null)", g_url);
  dnReleaseDevice(dev);

  setenv("DN_SERVER", "localhost:7878", 1);
  dev = dnNewDevice(NULL);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "$DN_SERVER");
  dnCommitDevice(dev);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_ARGUMENT, "'localhost:7878'");
  dnReleaseDevice(dev);
  unsetenv("DN_SERVER");
}

/* The filter holds its device: releasing the device first is fine. */
static void test_lifetimes(void) {
  printf("lifetimes\n");
  DNDevice dev = connected_device();
  static float color[W * H * 3], out[W * H * 3];
  color[5] = 3.0f;
  DNFilter f = passthrough_filter(dev, color, out);
  dnRetainFilter(f);
  dnReleaseDevice(dev);
  dnExecuteFilterAsync(f);
  dnReleaseFilter(f); /* one reference left */
  dnSyncFilter(f);
  CHECK(out[5] == 3.0f, "output after the device's release %g", out[5]);
  dnReleaseFilter(f); /* closes the session and the connection */
}

static void sleep_ms(long ms) {
  struct timespec t;
  t.tv_sec = ms / 1000;
  t.tv_nsec = (ms % 1000) * 1000000L;
  nanosleep(&t, NULL);
}

/* `c_api_test URL reconnect`: the server is killed and restarted on the same
 * address by the caller after "serving" is printed. The lost connection is
 * DN_ERROR_CONNECTION, dnCommitDevice connects again, the filter's next frame
 * asks for dnCommitFilter, which opens a new session. */
static void test_reconnect(void) {
  printf("reconnect\n");
  DNDevice dev = connected_device();
  static float color[W * H * 3], out[W * H * 3];
  color[7] = 2.5f;
  DNFilter f = passthrough_filter(dev, color, out);
  dnExecuteFilter(f);
  EXPECT_OK(dev, "before the server goes");
  const uint64_t first_session = dnGetFilterSessionId(f);
  printf("serving\n");
  fflush(stdout);

  const char* message = "";
  DNError code = DN_ERROR_NONE;
  for (int i = 0; i < 3000 && code == DN_ERROR_NONE; ++i) { /* frames until the server is gone (60 s at most) */
    dnExecuteFilter(f);
    code = dnGetDeviceError(dev, &message);
    if (code == DN_ERROR_NONE) sleep_ms(20);
  }
  CHECK(code == DN_ERROR_CONNECTION, "the server's loss gave error %d: %s", (int)code, message);
  printf("  lost: %s\n", message);

  for (int i = 0; i < 600; ++i) { /* connect again once it is back (60 s at most) */
    dnCommitDevice(dev);
    code = dnGetDeviceError(dev, &message);
    if (code == DN_ERROR_NONE) break;
    sleep_ms(100);
  }
  CHECK(code == DN_ERROR_NONE, "no reconnection: %s", message);
  dnExecuteFilter(f);
  EXPECT_ERROR(dev, DN_ERROR_INVALID_OPERATION, "reconnected");
  dnCommitFilter(f);
  out[7] = 0.0f;
  dnExecuteFilter(f);
  EXPECT_OK(dev, "after dnCommitDevice and dnCommitFilter");
  CHECK(out[7] == 2.5f, "output after the reconnection %g", out[7]);
  CHECK(dnGetFilterSessionId(f) != first_session, "the same session id after a new server");
  dnReleaseFilter(f);
  dnReleaseDevice(dev);
}

int main(int argc, char** argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s SERVER_URL [reconnect]\n", argv[0]);
    return 2;
  }
  g_url = argv[1];
  if (argc > 2 && strcmp(argv[2], "reconnect") == 0) {
    test_reconnect();
    printf("c_api_test: %d checks, %d failed\n", g_checks, g_failures);
    return g_failures ? 1 : 0;
  }
  test_passthrough_packed();
  test_passthrough_strided();
  test_auto();
  test_accumulate(0);
  test_accumulate(1);
  test_errors();
  test_default_address();
  test_lifetimes();
  printf("c_api_test: %d checks, %d failed\n", g_checks, g_failures);
  return g_failures ? 1 : 0;
}
