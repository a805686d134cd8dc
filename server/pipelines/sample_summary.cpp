#include "pipelines/sample_summary.hpp"

#include <bit>
#include <cstring>
#include <vector>

namespace dn::pipelines {

namespace {

PassSpec& add_summary_pass(GraphSpec& g) {
  g.add_readback(kSampleSummary, kSampleSummaryBytes);
  PassSpec& pass = g.add_pass("sample_summary", "sample_summary");
  pass.bind("summary", kSampleSummary);
  // Pixels per invocation: runs of equal bins are added at once.
  constexpr uint32_t kRun = 64;
  pass.set("RUN", kRun);
  pass.pixels_per_invocation = kRun;
  return pass;
}

}  // namespace

void add_sample_summary(GraphSpec& g, const std::string& history, const std::string& still) {
  PassSpec& pass = add_summary_pass(g);
  pass.bind("history", history);
  if (!still.empty()) pass.bind("still", still).set("STILL", 1u);
}

void add_sample_count_summary(GraphSpec& g, const std::string& counts) {
  add_summary_pass(g).bind("counts", counts).set("COUNTS", 1u);
}

uint32_t sample_bin(uint32_t count) {
  if (count < 32) return count;
  const uint32_t octave = std::min<uint32_t>(std::bit_width(count) - 1, 20);
  const uint32_t sub = count >= (1u << 21) ? 15 : (count >> (octave - 4)) & 15;
  return 32 + (octave - 5) * 16 + sub;
}

uint32_t sample_bin_floor(uint32_t bin) {
  if (bin < 32) return bin;
  const uint32_t octave = 5 + (bin - 32) / 16, sub = (bin - 32) % 16;
  return (16 + sub) << (octave - 4);
}

std::optional<SampleCounts> decode_sample_summary(std::span<const uint8_t> bytes) {
  std::vector<uint32_t> words(1 + kSampleBins, 0);
  std::memcpy(words.data(), bytes.data(), std::min(bytes.size(), words.size() * 4));
  uint64_t pixels = 0;
  for (uint32_t b = 0; b < kSampleBins; ++b) pixels += words[1 + b];
  if (pixels == 0) return std::nullopt;
  SampleCounts counts;
  counts.min = 0xffffffffu - words[0];
  // The lower median: the bin holding pixel (pixels + 1) / 2 in count order.
  const uint64_t half = (pixels + 1) / 2;
  uint64_t seen = 0;
  for (uint32_t b = 0; b < kSampleBins; ++b) {
    seen += words[1 + b];
    if (seen >= half) {
      counts.median = std::max(sample_bin_floor(b), counts.min);
      break;
    }
  }
  return counts;
}

}  // namespace dn::pipelines
