// Encode and decode cost of one 1280x720 FRAME with the SVGF channel set,
// fp32 and fp16: the protocol's share of the transport's time.
#include <benchmark/benchmark.h>

#include "frame_set.hpp"

namespace {

using dn::protocol::Format;

void BM_EncodeFrame(benchmark::State& state) {
  const Format format = state.range(0) == 16 ? Format::F16 : Format::F32;
  auto data = dn::bench::make_frame(1280, 720, dn::bench::svgf_channels(format));
  std::vector<uint8_t> out;
  for (auto _ : state) {
    out.clear();
    dn::protocol::encode(data.frame, 1, 0, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(out.size()));
}

void BM_DecodeFrame(benchmark::State& state) {
  const Format format = state.range(0) == 16 ? Format::F16 : Format::F32;
  auto data = dn::bench::make_frame(1280, 720, dn::bench::svgf_channels(format));
  auto bytes = dn::protocol::encode(data.frame, 1, 0);
  dn::protocol::Header header;
  dn::protocol::decode_header(bytes, 1ull << 31, header);
  std::span<const uint8_t> payload(bytes.data() + dn::protocol::kHeaderSize, header.payload_length);
  for (auto _ : state) {
    dn::protocol::Message message;
    auto err = dn::protocol::decode_payload(header, payload, message);
    benchmark::DoNotOptimize(err);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(bytes.size()));
}

BENCHMARK(BM_EncodeFrame)->Arg(32)->Arg(16)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeFrame)->Arg(32)->Arg(16)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
