#include "presets.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

namespace dn::cli {

using protocol::ChannelId;

namespace {

const char* cname(ChannelId id) {
  const auto* c = protocol::find_channel(id);
  return c ? c->name.data() : "?";
}
uint32_t components(ChannelId id) {
  const auto* c = protocol::find_channel(id);
  return c ? c->components : 0;
}

// Component suffix sets tried for a layer, by component count.
const std::vector<std::vector<std::string>>& suffix_sets(uint32_t n) {
  static const std::vector<std::vector<std::string>> one = {{"Y"}, {"Z"}, {"R"}, {"V"}, {"X"}, {"A"}};
  static const std::vector<std::vector<std::string>> two = {{"X", "Y"}, {"R", "G"}, {"U", "V"}, {"x", "y"}};
  static const std::vector<std::vector<std::string>> three = {
      {"R", "G", "B"}, {"X", "Y", "Z"}, {"r", "g", "b"}, {"x", "y", "z"}};
  static const std::vector<std::vector<std::string>> none;
  return n == 1 ? one : n == 2 ? two : n == 3 ? three : none;
}

bool has(const std::vector<std::string>& chans, const std::string& name) {
  return std::find(chans.begin(), chans.end(), name) != chans.end();
}

// Layer names to try for a term: as given, then with the view-layer prefix.
std::vector<std::string> layer_candidates(const std::string& layer, const std::string& prefix) {
  std::vector<std::string> out{layer};
  if (!prefix.empty() && layer.rfind(prefix + ".", 0) != 0) out.push_back(prefix + "." + layer);
  return out;
}

std::optional<std::vector<std::string>> resolve_term(const TermSpec& t, uint32_t n,
                                                     const std::vector<std::string>& chans,
                                                     const std::string& prefix) {
  if (!t.channels.empty()) {
    if (t.channels.size() != n) return std::nullopt;
    std::vector<std::string> out;
    for (const auto& c : t.channels) {
      std::optional<std::string> found;
      for (const auto& cand : layer_candidates(c, prefix))
        if (has(chans, cand)) {
          found = cand;
          break;
        }
      if (!found) return std::nullopt;
      out.push_back(*found);
    }
    return out;
  }
  for (const auto& layer : layer_candidates(t.layer, prefix)) {
    if (n == 1 && has(chans, layer)) return std::vector<std::string>{layer};
    for (const auto& set : suffix_sets(n)) {
      std::vector<std::string> out;
      for (const auto& s : set) out.push_back(layer + "." + s);
      if (std::all_of(out.begin(), out.end(), [&](const std::string& c) { return has(chans, c); })) return out;
    }
  }
  return std::nullopt;
}

TermSpec L(std::string layer) { return TermSpec{{}, std::move(layer)}; }
ChannelSpec spec(ChannelId id, std::vector<RecipeSpec> alts) { return ChannelSpec{id, std::move(alts), false}; }

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return {};
  const size_t b = s.find_last_not_of(" \t");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  size_t start = 0;
  for (;;) {
    const size_t p = s.find(sep, start);
    out.push_back(trim(s.substr(start, p == std::string::npos ? std::string::npos : p - start)));
    if (p == std::string::npos) break;
    start = p + 1;
  }
  return out;
}

std::string detect_cycles_layer(const std::vector<std::string>& chans) {
  // "<layer>.Combined.R" -> "<layer>" (first in sorted order: deterministic).
  const std::string key = ".Combined.R";
  for (const auto& c : chans)
    if (c.size() > key.size() && c.compare(c.size() - key.size(), key.size(), key) == 0)
      return c.substr(0, c.size() - key.size());
  return {};
}

}  // namespace

Preset make_preset(const std::string& name_in, const std::vector<std::string>& chans, const std::string& view_layer) {
  std::string name = name_in;
  const std::string detected = view_layer.empty() ? detect_cycles_layer(chans) : view_layer;
  if (name == "auto") name = detected.empty() ? "dnrender" : "cycles";

  Preset p;
  p.name = name;
  if (name == "dnrender") {
    // The example renderer's layout: one layer per protocol channel, named
    // like the channel; camera in the dn.* header attributes.
    p.channels = {
        spec(ChannelId::Radiance, {{{L("radiance")}}, {{TermSpec{{"R", "G", "B"}, {}}}}}),
        spec(ChannelId::Diffuse, {{{L("diffuse")}}}),
        spec(ChannelId::Specular, {{{L("specular")}}}),
        spec(ChannelId::Albedo, {{{L("albedo")}}}),
        spec(ChannelId::SpecularF0, {{{L("specular_f0")}}}),
        spec(ChannelId::Roughness, {{{L("roughness")}}}),
        spec(ChannelId::Normal, {{{L("normal")}}}),
        spec(ChannelId::Depth, {{{L("depth")}}}),
        spec(ChannelId::Motion, {{{L("motion")}}}),
        spec(ChannelId::Emission, {{{L("emission")}}}),
        spec(ChannelId::Position, {{{L("position")}}}),
        spec(ChannelId::SampleCount, {{{L("sample_count")}}}),
    };
    return p;
  }
  if (name == "cycles") {
    p.layer_prefix = detected.empty() ? "ViewLayer" : detected;
    const std::string P = p.layer_prefix + ".";
    p.channels = {
        spec(ChannelId::Radiance, {{{L(P + "Combined")}}}),
        spec(ChannelId::Diffuse, {{{L(P + "DiffDir"), L(P + "DiffInd")}}}),
        spec(ChannelId::Specular, {{{L(P + "GlossDir"), L(P + "GlossInd")}}}),
        spec(ChannelId::Albedo, {{{L(P + "DiffCol")}}}),
        spec(ChannelId::SpecularF0, {{{L(P + "GlossCol")}}}),
        // No built-in Cycles pass; a value AOV named "Roughness" is picked up.
        spec(ChannelId::Roughness, {{{L(P + "Roughness")}}}),
        spec(ChannelId::Normal, {{{L(P + "Normal")}}}),
        spec(ChannelId::Depth, {{{L(P + "Depth")}, Convert::CyclesDepth}}),
        spec(ChannelId::Motion, {{{TermSpec{{P + "Vector.X", P + "Vector.Y"}, {}}}, Convert::CyclesVector}}),
        spec(ChannelId::Emission, {{{L(P + "Emit"), L(P + "Env")}}, {{L(P + "Emit")}}}),
        spec(ChannelId::Position, {{{L(P + "Position")}}}),
    };
    return p;
  }
  throw ChannelMapError("unknown preset '" + name_in + "' (expected dnrender, cycles or auto)");
}

ChannelSpec parse_channel_override(const std::string& assignment) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == assignment.size())
    throw ChannelMapError("--channel expects NAME=SPEC (e.g. albedo=ViewLayer.DiffCol), got '" + assignment + "'");
  const std::string name = trim(assignment.substr(0, eq));
  std::string rhs = trim(assignment.substr(eq + 1));
  const auto* info = protocol::find_channel(name);
  if (!info || info->id == ChannelId::Output) {
    std::string names;
    for (const auto& c : protocol::kChannels)
      if (c.id != ChannelId::Output) names += (names.empty() ? "" : ", ") + std::string(c.name);
    throw ChannelMapError("--channel " + assignment + ": unknown protocol channel '" + name + "' (one of: " + names +
                          ")");
  }
  RecipeSpec r;
  if (const size_t at = rhs.rfind('@'); at != std::string::npos) {
    const std::string conv = rhs.substr(at + 1);
    rhs = trim(rhs.substr(0, at));
    if (conv != "cycles")
      throw ChannelMapError("--channel " + assignment + ": unknown conversion '@" + conv + "' (only @cycles)");
    if (info->id == ChannelId::Depth) r.convert = Convert::CyclesDepth;
    else if (info->id == ChannelId::Motion) r.convert = Convert::CyclesVector;
    else throw ChannelMapError("--channel " + assignment + ": @cycles applies to depth and motion only");
  }
  for (const auto& term : split(rhs, '+')) {
    if (term.empty()) throw ChannelMapError("--channel " + assignment + ": empty term");
    TermSpec t;
    if (term.find(',') != std::string::npos) {
      t.channels = split(term, ',');
      if (t.channels.size() != info->components)
        throw ChannelMapError("--channel " + assignment + ": '" + term + "' lists " +
                              std::to_string(t.channels.size()) + " EXR channels, '" + name + "' has " +
                              std::to_string(info->components) + " components");
      for (const auto& c : t.channels)
        if (c.empty()) throw ChannelMapError("--channel " + assignment + ": empty channel name in '" + term + "'");
    } else {
      t.layer = term;
    }
    r.terms.push_back(std::move(t));
  }
  return ChannelSpec{info->id, {std::move(r)}, true};
}

std::string ResolvedChannel::describe() const {
  std::string out;
  for (const auto& t : terms) {
    if (!out.empty()) out += " + ";
    if (t.size() == 1) {
      out += t[0];
      continue;
    }
    // Common "layer." prefix -> "layer.{R,G,B}"
    const size_t dot = t[0].rfind('.');
    const std::string pre = dot == std::string::npos ? std::string() : t[0].substr(0, dot + 1);
    bool common = !pre.empty();
    for (const auto& c : t) common = common && c.rfind(pre, 0) == 0 && c.find('.', pre.size()) == std::string::npos;
    if (common) {
      out += pre + "{";
      for (size_t i = 0; i < t.size(); ++i) out += (i ? "," : "") + t[i].substr(pre.size());
      out += "}";
    } else {
      for (size_t i = 0; i < t.size(); ++i) out += (i ? "," : "") + t[i];
    }
  }
  if (convert == Convert::CyclesDepth) out += " (Cycles depth)";
  if (convert == Convert::CyclesVector) out += " (Cycles vector)";
  return out;
}

std::optional<ResolvedChannel> resolve(const ChannelSpec& s, const std::vector<std::string>& chans,
                                       const std::string& prefix) {
  const uint32_t n = components(s.id);
  for (const auto& alt : s.alternatives) {
    ResolvedChannel r{s.id, {}, alt.convert};
    bool ok = !alt.terms.empty();
    for (const auto& t : alt.terms) {
      auto term = resolve_term(t, n, chans, prefix);
      if (!term) {
        ok = false;
        break;
      }
      r.terms.push_back(std::move(*term));
    }
    if (ok) return r;
  }
  return std::nullopt;
}

std::string describe_tried(const ChannelSpec& s, const std::string& prefix) {
  std::string out;
  for (const auto& alt : s.alternatives) {
    std::string one;
    for (const auto& t : alt.terms) {
      if (!one.empty()) one += " + ";
      if (!t.channels.empty()) {
        for (size_t i = 0; i < t.channels.size(); ++i) one += (i ? "," : "") + t.channels[i];
      } else {
        const auto cands = layer_candidates(t.layer, prefix);
        for (size_t i = 0; i < cands.size(); ++i) one += (i ? "|" : "") + cands[i];
      }
    }
    out += (out.empty() ? "" : "; ") + one;
  }
  std::string suffixes;
  for (const auto& set : suffix_sets(components(s.id))) {
    std::string a;
    for (const auto& x : set) a += (a.empty() ? "" : ",") + x;
    suffixes += (suffixes.empty() ? "" : " or ") + ("." + (set.size() > 1 ? "{" + a + "}" : a));
  }
  return out + " (layers with components " + suffixes + ")";
}

std::vector<ChannelId> parse_channel_list(const std::string& list) {
  std::vector<ChannelId> out;
  for (const auto& name : split(list, ',')) {
    const auto* c = protocol::find_channel(name);
    if (!c || c->id == ChannelId::Output) throw ChannelMapError("--channels: unknown protocol channel '" + name + "'");
    if (std::find(out.begin(), out.end(), c->id) != out.end())
      throw ChannelMapError("--channels: '" + name + "' listed twice");
    out.push_back(c->id);
  }
  return out;
}

std::vector<ResolvedChannel> plan_channels(const Preset& preset, const std::vector<ChannelSpec>& overrides,
                                           const protocol::PipelineInfo* pipeline,
                                           const std::optional<std::vector<ChannelId>>& only,
                                           const std::vector<std::string>& chans, const std::string& file) {
  // The spec used for each channel: an override replaces the preset's.
  auto spec_for = [&](ChannelId id) -> std::optional<ChannelSpec> {
    for (const auto& o : overrides)
      if (o.id == id) return o;
    for (const auto& s : preset.channels)
      if (s.id == id) return s;
    return std::nullopt;
  };
  auto missing = [&](ChannelId id, const std::string& why) -> ChannelMapError {
    auto s = spec_for(id);
    std::string tried = s ? describe_tried(*s, preset.layer_prefix) : "nothing (no mapping in preset '" + preset.name + "')";
    return ChannelMapError(why + " channel '" + cname(id) + "', but " + file + " has none of the EXR layers tried: " +
                           tried + "; map it with --channel " + cname(id) + "=LAYER");
  };

  std::vector<ChannelId> wanted;
  std::set<ChannelId> must;  // missing -> error
  auto want = [&](ChannelId id, bool required) {
    if (std::find(wanted.begin(), wanted.end(), id) == wanted.end()) wanted.push_back(id);
    if (required) must.insert(id);
  };
  const std::string pname = pipeline ? "pipeline '" + pipeline->name + "' requires" : "this run needs";

  if (only) {
    for (auto id : *only) want(id, true);
  } else {
    for (const auto& o : overrides) want(o.id, true);
    if (pipeline) {
      for (const auto& c : protocol::kChannels)
        if (pipeline->required_channels & protocol::channel_bit(c.id)) want(c.id, true);
      const bool radiance_sent = std::find(wanted.begin(), wanted.end(), ChannelId::Radiance) != wanted.end() ||
                                 ((pipeline->optional_channels & protocol::channel_bit(ChannelId::Radiance)) &&
                                  spec_for(ChannelId::Radiance) && resolve(*spec_for(ChannelId::Radiance), chans,
                                                                           preset.layer_prefix));
      for (const auto& c : protocol::kChannels) {
        if (!(pipeline->optional_channels & protocol::channel_bit(c.id))) continue;
        if (radiance_sent && (c.id == ChannelId::Diffuse || c.id == ChannelId::Specular)) continue;
        auto s = spec_for(c.id);
        if (s && resolve(*s, chans, preset.layer_prefix)) want(c.id, false);
      }
    } else {
      for (ChannelId id : {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth,
                           ChannelId::Motion}) {
        auto s = spec_for(id);
        if (s && resolve(*s, chans, preset.layer_prefix)) want(id, id == ChannelId::Radiance);
      }
      if (wanted.empty() || wanted.front() != ChannelId::Radiance) want(ChannelId::Radiance, true);
    }
  }

  std::vector<ResolvedChannel> out;
  for (ChannelId id : wanted) {
    auto s = spec_for(id);
    std::optional<ResolvedChannel> r = s ? resolve(*s, chans, preset.layer_prefix) : std::nullopt;
    if (!r) {
      if (must.count(id)) {
        bool overridden = std::any_of(overrides.begin(), overrides.end(), [&](auto& o) { return o.id == id; });
        throw missing(id, overridden ? "--channel maps" : (only ? "--channels lists" : pname));
      }
      continue;
    }
    out.push_back(std::move(*r));
  }
  // Protocol order (by id) keeps the session's declaration stable.
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return uint8_t(a.id) < uint8_t(b.id); });
  return out;
}

void convert_cycles_depth(std::span<float> depth) {
  for (float& d : depth)
    if (!std::isfinite(d) || d >= 1e9f) d = std::numeric_limits<float>::infinity();
}

void convert_cycles_vector(std::span<float> xy) {
  for (size_t i = 1; i < xy.size(); i += 2) xy[i] = -xy[i];
}

}  // namespace dn::cli
