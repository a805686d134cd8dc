// dn: command-line client of dnserver.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"

namespace {

std::string help() {
  return std::string(
             "usage: dn <command> [options]\n"
             "\n"
             "commands:\n"
             "  denoise   denoise an image or a sequence (EXR, PFM, PNG) through a server session\n"
             "  watch     attach to a running session and write its newest frames\n"
             "  preview   attach to a running session and show it live in a browser\n"
             "  ping      handshake, server limits and pipelines, round-trip time\n"
             "  pipelines the server's pipelines: channels and parameter tables\n"
             "  stats     print the server's statistics\n"
             "  capacity  how many more sessions of a size and pipeline the server can take\n"
             "\n"
             "'dn <command> --help' lists the options of a command. The server address is\n"
             "--server tcp://HOST:PORT or unix:///path; without it $DN_SERVER, else\n") +
         dn::client::kDefaultServerUrl +
         " (dnserver's default). The auth token comes from --token-file,\n"
         "$DN_TOKEN or $DN_TOKEN_FILE.\n"
         "\n"
         "exit status: 0 success, 1 error (server, connection, files), 2 bad command line,\n"
         "3 dn denoise --fail threshold exceeded.\n";
}

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    std::fputs(help().c_str(), argc < 2 ? stderr : stdout);
    return argc < 2 ? dn::cli::kExitUsage : dn::cli::kExitOk;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::printf("dn %s\n", dn::client::kClientVersion);
    return dn::cli::kExitOk;
  }
  const std::string cmd = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  try {
    if (cmd == "denoise") return dn::cli::run_denoise(args);
    if (cmd == "watch") return dn::cli::run_watch(args);
    if (cmd == "preview") return dn::cli::run_preview(args);
    if (cmd == "ping") return dn::cli::run_ping(args);
    if (cmd == "pipelines") return dn::cli::run_pipelines(args);
    if (cmd == "stats") return dn::cli::run_stats(args);
    if (cmd == "capacity") return dn::cli::run_capacity(args);
    std::fprintf(stderr, "dn: unknown command '%s' (expected denoise, watch, preview, ping, pipelines, stats or capacity)\n", cmd.c_str());
    return dn::cli::kExitUsage;
  } catch (const dn::cli::UsageError& e) {
    std::fprintf(stderr, "dn %s: %s\n", cmd.c_str(), one_line(e.what()).c_str());
    return dn::cli::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dn %s: error: %s\n", cmd.c_str(), one_line(e.what()).c_str());
    return dn::cli::kExitError;
  }
}
