/* Compiles against the installed dn/dn.h and links libdn (through the CMake
 * target dn::c, and with `pkg-config --cflags --libs dn`); exercises calls
 * that need no server. */
#include <dn/dn.h>

#include <stdio.h>
#include <string.h>

int main(void) {
  const char* message = NULL;
  DNDevice dev = dnNewDevice("unix:///nonexistent/dnclient-c-consumer.sock");
  dnSetDevice1i(dev, "connect_timeout_ms", 500);
  dnCommitDevice(dev);
  if (dnGetDeviceError(dev, &message) != DN_ERROR_CONNECTION || !strstr(message, "dnclient-c-consumer.sock")) {
    fprintf(stderr, "expected a connection error naming the socket, got: %s\n", message ? message : "(null)");
    return 1;
  }
  printf("dn c consumer ok (libdn %d.%d: %s)\n", DN_VERSION_MAJOR, DN_VERSION_MINOR, message);
  if (dnNewFilter(dev, "passthrough") != NULL || dnGetDeviceError(dev, &message) != DN_ERROR_INVALID_OPERATION)
    return 1;
  dnReleaseDevice(dev);
  return 0;
}
