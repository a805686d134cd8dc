// dnserver: the denoising service's long-lived process.
#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <exception>

#include "server/cache_dir.hpp"
#include "server/gpu/context.hpp"
#include "server/gpu/devices.hpp"
#include "server/idle_trim.hpp"
#include "server/log.hpp"
#include "server/options.hpp"
#include "server/server.hpp"

int main(int argc, char** argv) {
  dn::server::ServerOptions options;
  auto parsed = dn::server::parse_options(argc, argv, options);
  if (parsed.exit_now) return 0;
  if (!parsed.ok) {
    std::fprintf(stderr, "dnserver: %s\n", parsed.error.c_str());
    return 2;
  }
  dn::log::Level level;
  dn::log::parse_level(options.log_level, level);
  dn::log::set_level(level);
  ::signal(SIGPIPE, SIG_IGN);
  dn::server::configure_allocator();
  // Block SIGTERM/SIGINT before any thread exists (workers, the Vulkan driver's
  // own), so every thread inherits the mask and the event loop's signalfd alone
  // receives them.
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGTERM);
  sigaddset(&mask, SIGINT);
  pthread_sigmask(SIG_BLOCK, &mask, nullptr);

  try {
    if (options.list_devices) {
      for (const auto& d : dn::gpu::Context::list_devices()) std::printf("%s\n", dn::gpu::format_device(d).c_str());
      return 0;
    }
    dn::gpu::ContextOptions device_options;
    device_options.device = options.device;
    device_options.validation = options.validation;
    device_options.pipeline_cache_dir = dn::server::resolve_cache_dir(options);
    dn::gpu::Context device(device_options);
    dn::server::Server server(options, device, device.name());
    server.run(/*handle_signals=*/true);
  } catch (const std::exception& e) {
    dn::log::error("fatal", {{"reason", e.what()}});
    std::fprintf(stderr, "dnserver: %s\n", e.what());
    return 1;
  }
  return 0;
}
