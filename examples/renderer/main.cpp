// dnrender: the example path tracer of the denoising service. See docs/renderer.md.
#include <cstdio>
#include <exception>

#include "cli.hpp"

int main(int argc, char** argv) {
  dn::render::CliOptions options;
  try {
    options = dn::render::parse_cli(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const dn::render::UsageError& e) {
    std::fprintf(stderr, "dnrender: %s\n(see dnrender --help)\n", e.what());
    return 2;
  }
  try {
    return dn::render::run_cli(options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dnrender: error: %s\n", e.what());
    return 1;
  }
}
