#include "pipelines/input_forms.hpp"

#include <algorithm>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "pipelines/graph.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;
using protocol::SampleField;

uint64_t bits(std::initializer_list<ChannelId> ids) {
  uint64_t mask = 0;
  for (ChannelId id : ids) mask |= protocol::channel_bit(id);
  return mask;
}

const uint64_t kSignals = bits({ChannelId::Radiance, ChannelId::Diffuse, ChannelId::DiffuseLighting,
                                ChannelId::Specular, ChannelId::SpecularLighting, ChannelId::SpecularAlbedo});
const uint64_t kStatistics = bits({ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3});

std::vector<uint64_t> signal_forms(const PipelineDescription& p) {
  const uint64_t accepted = p.required_channels | p.optional_channels;
  const uint64_t radiance = bits({ChannelId::Radiance});
  if (p.required_channels & radiance) return {radiance};
  std::vector<uint64_t> forms;
  if (accepted & radiance) forms.push_back(radiance);
  for (uint64_t diffuse : {bits({ChannelId::Diffuse}), bits({ChannelId::DiffuseLighting})})
    for (uint64_t specular : {bits({ChannelId::Specular}), bits({ChannelId::SpecularLighting, ChannelId::SpecularAlbedo})})
      if (((diffuse | specular) & ~accepted) == 0) forms.push_back(diffuse | specular);
  return forms;
}

// The channels of k extra samples for a signal form; 0 where it takes none.
uint64_t extra_samples(uint64_t signals, uint32_t k) {
  std::vector<SampleField> colours;
  if (signals == bits({ChannelId::Radiance})) colours = {SampleField::Radiance};
  else if (signals == bits({ChannelId::Diffuse, ChannelId::Specular})) colours = {SampleField::Diffuse, SampleField::Specular};
  else return 0;
  uint64_t mask = 0;
  for (uint32_t j = 1; j <= k; ++j) {
    for (SampleField f : colours) mask |= protocol::channel_bit(protocol::sample_channel(j, f));
    for (SampleField f : {SampleField::Normal, SampleField::Depth, SampleField::Offset})
      mask |= protocol::channel_bit(protocol::sample_channel(j, f));
  }
  return mask;
}

// A kernel: a shader with one specialization.
using Kernel = std::pair<std::string_view, std::vector<gpu::SpecConstant>>;

std::set<Kernel> kernels_of(const GraphSpec& graph) {
  std::set<Kernel> out;
  for (const PassSpec& pass : graph.passes) out.insert({pass.shader(), kernel_desc(pass, 64).spec_constants});
  return out;
}

// Every form prepare() accepts, each with its prepared graph (prepared once).
std::vector<std::pair<uint64_t, PreparedPipeline>> prepared_forms(const PipelineDescription& p) {
  const uint64_t base = p.required_channels & ~kSignals;
  const bool reads_extras = p.name != "passthrough";
  // Optional channels read one by one: all but the signals, the statistics
  // (all four or none) and the extra samples (0 to 3 per signal form).
  const uint64_t samples = extra_samples(bits({ChannelId::Radiance}), protocol::kMaxExtraSamples) |
                           extra_samples(bits({ChannelId::Diffuse, ChannelId::Specular}), protocol::kMaxExtraSamples);
  std::vector<uint64_t> extras;
  for (const auto& c : protocol::kChannels) {
    const uint64_t bit = protocol::channel_bit(c.id);
    if (reads_extras && (p.optional_channels & bit) && !(bit & (kSignals | kStatistics | samples))) extras.push_back(bit);
  }
  if (reads_extras && (p.optional_channels & kStatistics) == kStatistics) extras.push_back(kStatistics);
  const bool takes_samples = reads_extras && (p.optional_channels & extra_samples(bits({ChannelId::Radiance}), 1)) != 0;

  std::vector<std::pair<uint64_t, PreparedPipeline>> forms;
  for (uint64_t signals : signal_forms(p))
    for (uint64_t subset = 0; subset < (uint64_t{1} << extras.size()); ++subset) {
      uint64_t form = base | signals;
      for (size_t i = 0; i < extras.size(); ++i)
        if (subset & (uint64_t{1} << i)) form |= extras[i];
      for (uint32_t k = 0; k <= (takes_samples && extra_samples(signals, 1) ? protocol::kMaxExtraSamples : 0); ++k) {
        const uint64_t with_samples = form | extra_samples(signals, k);
        if (((with_samples & ~(p.required_channels | p.optional_channels))) != 0) continue;
        auto prepared = prepare(form_config(p, with_samples, 64, 64));
        if (auto* ok = std::get_if<PreparedPipeline>(&prepared)) forms.emplace_back(with_samples, std::move(*ok));
      }
    }
  return forms;
}

}  // namespace

SessionConfig form_config(const PipelineDescription& pipeline, uint64_t form, uint32_t width, uint32_t height) {
  SessionConfig config;
  config.width = width;
  config.height = height;
  config.pipeline = pipeline.name;
  for (const auto& c : protocol::kChannels)
    if (form & protocol::channel_bit(c.id)) config.channels.push_back({c.id, protocol::Format::F32});
  return config;
}

std::vector<uint64_t> input_forms(const PipelineDescription& p) {
  std::vector<uint64_t> forms;
  for (const auto& [form, prepared] : prepared_forms(p)) forms.push_back(form);
  return forms;
}

KernelVariants kernel_variants(const PipelineDescription& pipeline) {
  std::vector<std::pair<uint64_t, std::set<Kernel>>> forms;
  for (const auto& [form, prepared] : prepared_forms(pipeline)) forms.emplace_back(form, kernels_of(prepared.graph()));
  // Greedy cover: the form adding most kernels not yet covered, first.
  KernelVariants out;
  out.forms = forms.size();
  std::set<Kernel> covered;
  for (;;) {
    size_t best = forms.size(), best_new = 0;
    for (size_t i = 0; i < forms.size(); ++i) {
      const size_t fresh = static_cast<size_t>(std::count_if(forms[i].second.begin(), forms[i].second.end(),
                                                             [&](const Kernel& k) { return !covered.count(k); }));
      if (fresh > best_new) best = i, best_new = fresh;
    }
    if (best == forms.size()) break;
    covered.insert(forms[best].second.begin(), forms[best].second.end());
    out.covering_forms.push_back(forms[best].first);
  }
  out.kernels = covered.size();
  return out;
}

}  // namespace dn::pipelines
