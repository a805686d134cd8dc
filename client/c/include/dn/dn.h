/* dn — the C API of the dnserver client, shaped like Intel Open Image Denoise.
 *
 *   DNDevice dev = dnNewDevice(NULL);              (NULL: $DN_SERVER, else tcp://127.0.0.1:7878)
 *   dnCommitDevice(dev);                           (connects: HELLO -> WELCOME)
 *   DNFilter f = dnNewFilter(dev, "svgf");         (a pipeline the server offers)
 *   dnSetSharedFilterImage(f, "color", rgb, DN_FORMAT_FLOAT3, w, h, 0, 0, 0);
 *   ... "albedo", "normal", "depth", "motion", "output"
 *   dnCommitFilter(f);                             (opens the session on the server)
 *   per frame: dnSetFilterCamera(f, view, proj, jitter); dnExecuteFilter(f);
 *   const char* msg;
 *   if (dnGetDeviceError(dev, &msg) != DN_ERROR_NONE) fprintf(stderr, "%s\n", msg);
 *   dnReleaseFilter(f); dnReleaseDevice(dev);
 *
 * A thin layer over the C++ library dn::client (docs/client.md, "C API").
 * No function aborts or lets an exception out: every error is recorded on the
 * device (dnGetDeviceError, dnSetDeviceErrorFunction); calls on a NULL handle
 * record it in a per-thread slot read with dnGetDeviceError(NULL, ...).
 * A device and its filters share one connection: use them from one thread at
 * a time (calls are serialized by a per-device lock), or one device per thread.
 * Pure C99; link with -ldn (pkg-config dn) or the CMake target dn::c.
 */
#ifndef DN_DN_H
#define DN_DN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#  if defined(DN_C_BUILDING)
#    define DN_API __declspec(dllexport)
#  else
#    define DN_API __declspec(dllimport)
#  endif
#else
#  define DN_API __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define DN_VERSION_MAJOR 0
#define DN_VERSION_MINOR 1
#define DN_VERSION_PATCH 0

/* Opaque handles, reference counted (dnRetain*, dnRelease*). A filter holds a
 * reference to its device. */
typedef struct DNDeviceImpl* DNDevice;
typedef struct DNFilterImpl* DNFilter;

/* Error codes. The first five have OIDN's values and meanings. */
typedef enum {
  DN_ERROR_NONE = 0,
  DN_ERROR_UNKNOWN = 1,            /* anything else (an internal error) */
  DN_ERROR_INVALID_ARGUMENT = 2,   /* a name, format, size, value, pipeline or image the call or the server refused */
  DN_ERROR_INVALID_OPERATION = 3,  /* a call out of order: a filter before dnCommitDevice, execute before commit */
  DN_ERROR_OUT_OF_MEMORY = 4,
  DN_ERROR_CONNECTION = 100,       /* the server could not be reached, the connection was lost, or it timed out */
  DN_ERROR_SERVER = 101,           /* the server refused for its own reasons: token, limits, device, shutting down */
  DN_ERROR_PROTOCOL = 102          /* the server sent something this library cannot decode */
} DNError;

/* Called on every error (not only the first), with the device's user pointer. */
typedef void (*DNErrorFunction)(void* userPtr, DNError code, const char* message);

/* Pixel formats of shared images; values as OIDN's. FLOAT* images travel as
 * fp32, HALF* as fp16 (IEEE binary16 bits in uint16_t). */
typedef enum {
  DN_FORMAT_UNDEFINED = 0,
  DN_FORMAT_FLOAT = 1,
  DN_FORMAT_FLOAT2 = 2,
  DN_FORMAT_FLOAT3 = 3,
  DN_FORMAT_FLOAT4 = 4,
  DN_FORMAT_HALF = 257,
  DN_FORMAT_HALF2 = 258,
  DN_FORMAT_HALF3 = 259,
  DN_FORMAT_HALF4 = 260
} DNFormat;

/* Motion-vector conventions (filter parameter "motion_convention"). */
typedef enum {
  DN_MOTION_PIXELS_TO_PREVIOUS = 0, /* default: p_prev = p + mv, pixels */
  DN_MOTION_PIXELS_TO_NEXT = 1,     /* p_prev = p - mv */
  DN_MOTION_UV_TO_PREVIOUS = 2      /* p_prev = p + mv * (width, height) */
} DNMotionConvention;

/* ---- Device: one connection to a dnserver --------------------------------- */

/* url: "tcp://HOST:PORT" or "unix:///path"; NULL or "" means $DN_SERVER, else
 * tcp://127.0.0.1:7878 (where dnserver listens without --listen). A malformed
 * address is recorded as the device's error (and again by dnCommitDevice).
 * Returns NULL only when out of memory. */
DN_API DNDevice dnNewDevice(const char* url);
DN_API void dnRetainDevice(DNDevice device);
DN_API void dnReleaseDevice(DNDevice device);

/* Settings, before dnCommitDevice:
 *   1s "url"          the server address (as dnNewDevice)
 *   1s "token"        the auth token (default: $DN_TOKEN, else the file named by $DN_TOKEN_FILE)
 *   1s "token_file"   a file whose first line is the token
 *   1s "client_name"  HELLO's client name (default "dn-c")
 *   1i "connect_timeout_ms"  connect + handshake (default 10000)
 *   1i "io_timeout_ms"       longest wait for one reply (default 120000; 0 = forever)
 * An unknown name is DN_ERROR_INVALID_ARGUMENT naming it. */
DN_API void dnSetDevice1s(DNDevice device, const char* name, const char* value);
DN_API void dnSetDevice1i(DNDevice device, const char* name, int value);
/* Read-only, after dnCommitDevice (NULL/0 and an error otherwise; "url" also
 * before it, as set):
 *   1s "url" (canonical), "server_version", "device_name" (the server's GPU),
 *      "pipelines" (comma-separated names)
 *   1i "version_major", "version_minor" (the protocol version agreed on),
 *      "max_width", "max_height", "max_frames_in_flight"
 * A returned string stays valid until the next call on the device. */
DN_API const char* dnGetDevice1s(DNDevice device, const char* name);
DN_API int dnGetDevice1i(DNDevice device, const char* name);

DN_API void dnSetDeviceErrorFunction(DNDevice device, DNErrorFunction func, void* userPtr);
/* The first error recorded since the last query, and clears it (OIDN's rule:
 * later errors do not overwrite an unqueried one). *outMessage (may be NULL)
 * is a message naming what was wrong, "" for DN_ERROR_NONE; it stays valid
 * until the next dnGetDeviceError on the device. device NULL: this thread's
 * errors from calls given NULL handles. */
DN_API DNError dnGetDeviceError(DNDevice device, const char** outMessage);

/* Connects and does the handshake. Again on a committed device: nothing. */
DN_API void dnCommitDevice(DNDevice device);

/* Waits for the frames in flight of every filter of the device (dnSyncFilter on each). */
DN_API void dnSyncDevice(DNDevice device);

/* ---- Filter: one session (one camera stream) ------------------------------ */

/* type: a pipeline the server offers ("passthrough", "accumulate", "svgf",
 * ...; dnGetDevice1s(dev, "pipelines")). Needs a committed device. Returns
 * NULL on error (an unknown pipeline names the ones offered). */
DN_API DNFilter dnNewFilter(DNDevice device, const char* type);
DN_API void dnRetainFilter(DNFilter filter);
/* The last release waits for nothing: frames in flight are dropped and the
 * session is closed. */
DN_API void dnReleaseFilter(DNFilter filter);

/* Images. name: OIDN's "color" (= "radiance"), "albedo", "normal", "output",
 * or any protocol channel name ("depth", "motion", "diffuse", "specular",
 * "roughness", "specular_f0", "emission", "position", "sample_count", ...;
 * docs/protocol.md). The format's component count must be the channel's
 * (color/albedo/normal/output: 3, motion: 2, depth: 1). All images have the
 * same width and height. Strides in bytes; 0 means packed
 * (bytePixelStride = the format's size, byteRowStride = width * bytePixelStride).
 * The memory is read (inputs) or written (output) by dnExecuteFilter /
 * dnSyncFilter, so it must stay valid until then. Changing which images are
 * set, their format or size needs dnCommitFilter; pointers and strides do not. */
DN_API void dnSetSharedFilterImage(DNFilter filter, const char* name, void* devPtr, DNFormat format,
                                   size_t width, size_t height, size_t byteOffset, size_t bytePixelStride,
                                   size_t byteRowStride);
DN_API void dnUnsetFilterImage(DNFilter filter, const char* name);

/* Parameters: the pipeline's (names, defaults and ranges: `dn pipelines`,
 * docs/pipelines.md), checked against the server's table when set, plus
 *   1b "hdr"                true only (the input is always linear HDR)
 *   1i "motion_convention"  a DNMotionConvention
 *   1b "share_input"        the session's watchers (dn preview) also see the noisy colour
 * Pipeline parameters and share_input take effect at dnCommitFilter. */
DN_API void dnSetFilter1b(DNFilter filter, const char* name, bool value);
DN_API void dnSetFilter1i(DNFilter filter, const char* name, int value);
DN_API void dnSetFilter1f(DNFilter filter, const char* name, float value);
/* The value set, else the pipeline's default (0 and an error for an unknown name). */
DN_API float dnGetFilter1f(DNFilter filter, const char* name);
DN_API int dnGetFilter1i(DNFilter filter, const char* name);

/* Opens the session with the images set as channels, or keeps the open one
 * (and its history) when size, channels, formats and parameters are
 * unchanged. A required image missing, sizes that differ, or a parameter the
 * server refuses is an error naming it; the filter then has no session until
 * the next successful commit. */
DN_API void dnCommitFilter(DNFilter filter);

/* Sends one frame (the images as they are now), waits for the result and
 * writes it into the "output" image. Frames in flight from
 * dnExecuteFilterAsync are collected first. */
DN_API void dnExecuteFilter(DNFilter filter);
/* Sends one frame and returns; its result is written into the output image
 * as it was set at this call by dnSyncFilter (or the next dnExecuteFilter).
 * The inputs may be reused on return. Blocks only while the server's window
 * of frames in flight is full. */
DN_API void dnExecuteFilterAsync(DNFilter filter);
/* Waits for every frame in flight and writes their outputs, in order. */
DN_API void dnSyncFilter(DNFilter filter);
/* How many input frames the last output written rests on per pixel, over
 * the frame (protocol 1.9): the fewest and the median. False (both 0) before
 * an output, from an older server, or from a pipeline that keeps no count. */
DN_API bool dnGetFilterSamples(DNFilter filter, uint32_t* outMin, uint32_t* outMedian);

/* Temporal inputs (OIDN has none). The camera of the next frames: view and
 * projection column-major 4x4 (GLM's layout), unjittered; jitter in pixels
 * (NULL: 0). Kept until set again; the previous frame's camera is sent along
 * automatically. Default: identity, no jitter. */
DN_API void dnSetFilterCamera(DNFilter filter, const float view[16], const float projection[16],
                              const float jitter[2]);
/* The next frame discards the history (a camera cut). */
DN_API void dnResetFilterHistory(DNFilter filter);

/* The open session, for `dn watch` (after dnCommitFilter; 0 / NULL before).
 * Strings stay valid until the next commit or release of the filter. */
DN_API uint64_t dnGetFilterSessionId(DNFilter filter);
DN_API const char* dnGetFilterWatchKey(DNFilter filter);     /* 32 hex digits ("" from a server before 1.6) */
DN_API const char* dnGetFilterWatchCommand(DNFilter filter); /* "DN_WATCH_KEY=KEY dn watch --server URL --session ID" */
/* The pipeline the session runs: for a filter of type "auto", the server's
 * choice, and why in one line ("" for a named type or a server before 1.10). */
DN_API const char* dnGetFilterPipeline(DNFilter filter);
DN_API const char* dnGetFilterPipelineReason(DNFilter filter);

#ifdef __cplusplus
}
#endif

#endif /* DN_DN_H */
