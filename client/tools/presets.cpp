#include "presets.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
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
    for (ChannelId id : {ChannelId::ReflectionPosition, ChannelId::ReflectionAlbedo, ChannelId::ReflectionNormal,
                         ChannelId::ReflectionDepth, ChannelId::ReflectionDirection, ChannelId::ReflectionDistance,
                         ChannelId::ReflectionFootprint})
      p.channels.push_back(spec(id, {{{L(std::string(protocol::find_channel(id)->name))}}}));
    for (uint32_t j = 1; j <= protocol::kMaxExtraSamples; ++j)
      for (uint32_t f = 0; f < 6; ++f) {
        const ChannelId id = protocol::sample_channel(j, static_cast<protocol::SampleField>(f));
        p.channels.push_back(spec(id, {{{L(std::string(protocol::find_channel(id)->name))}}}));
      }
    // dnrender --stats: stat_count.Y, stat_mean.R/G/B, ... (docs/protocol.md §7.7).
    for (ChannelId id : {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3})
      p.channels.push_back(spec(id, {{{L(std::string(protocol::find_channel(id)->name))}}}));
    return p;
  }
  if (name == "cycles") {
    // docs/client.md, "Blender Cycles": Cycles' lighting passes are already
    // divided by their colour passes, Combined = (DiffDir + DiffInd) x DiffCol
    // + (GlossDir + GlossInd) x GlossCol + (TransDir + TransInd) x TransCol
    // + Emit + Env + VolumeDir + VolumeInd.
    p.layer_prefix = detected.empty() ? "ViewLayer" : detected;
    const std::string P = p.layer_prefix + ".";
    auto times = [&](const std::string& layer, const std::string& colour, bool optional = false) {
      return TermSpec{{}, P + layer, P + colour, optional};
    };
    auto opt = [&](const std::string& layer) { return TermSpec{{}, P + layer, {}, true}; };
    const SourceSpec position{P + "Position", 3};
    p.channels = {
        spec(ChannelId::Radiance, {{{L(P + "Combined")}}}),
        spec(ChannelId::DiffuseLighting, {{{L(P + "DiffDir"), L(P + "DiffInd")}}}),
        spec(ChannelId::SpecularLighting, {{{L(P + "GlossDir"), L(P + "GlossInd")}}}),
        spec(ChannelId::SpecularAlbedo, {{{L(P + "GlossCol")}}}),
        // Radiance forms, for pipelines that demodulate themselves (svgf-fb's F_beta).
        spec(ChannelId::Diffuse, {{{times("DiffDir", "DiffCol"), times("DiffInd", "DiffCol")}}}),
        spec(ChannelId::Specular, {{{times("GlossDir", "GlossCol"), times("GlossInd", "GlossCol")}}}),
        spec(ChannelId::Albedo, {{{L(P + "DiffCol")}}}),
        // No built-in Cycles passes: shader AOVs named "SpecularF0" (colour) and "Roughness" (value).
        spec(ChannelId::SpecularF0, {{{L(P + "SpecularF0")}}}),
        spec(ChannelId::Roughness, {{{L(P + "Roughness")}}}),
        spec(ChannelId::Normal, {{{L(P + "Normal")}}}),
        // Past a mirror, the depth of what it reflects (rough_guides below).
        spec(ChannelId::Depth,
             {{{L(P + "Denoising Depth")}, Convert::CyclesVirtualDepth, true}, {{L(P + "Depth")}, Convert::CyclesDepth}}),
        spec(ChannelId::Motion, {{{TermSpec{{P + "Vector.X", P + "Vector.Y"}, {}}}, Convert::CyclesVector}}),
        spec(ChannelId::Emission, {{{L(P + "Emit"), opt("Env")}}}),
        spec(ChannelId::Position, {{{L(P + "Position")}}}),
        // Reflection features (reflect; docs/client.md): what the Denoising
        // Data passes say of the first non-specular hit, plus the mirror
        // direction and its hit, derived with the camera
        // (derive_reflection_features). On glossy surfaces (Cycles follows
        // bounces up to roughness 0.27) the passes describe one sampled
        // reflection; measured, that still beats the primary hit's features
        // there (docs/client.md), so they are not rough-guided.
        // Denoising Albedo includes the mirror's own reflectance, which the
        // protocol leaves to F_beta: the server divides and multiplies by the
        // same product, and dividing it out measured worse (docs/client.md).
        spec(ChannelId::ReflectionAlbedo, {{{L(P + "Denoising Albedo")}}}),
        // The derivations read the Position pass (and the hit the Denoising Depth).
        spec(ChannelId::ReflectionNormal, {{{L(P + "Denoising Normal")}, Convert::CyclesCameraNormal}}),
        spec(ChannelId::ReflectionDepth, {{{L(P + "Denoising Depth")}, Convert::CyclesChainDepth, false, {position}}}),
        spec(ChannelId::ReflectionDirection, {{{L(P + "Normal")}, Convert::CyclesMirrorDirection, false, {position}}}),
        spec(ChannelId::ReflectionDistance,
             {{{L(P + "Denoising Depth")}, Convert::CyclesChainLength, false, {position}}}),
        spec(ChannelId::ReflectionPosition,
             {{{L(P + "Position")}, Convert::CyclesChainHit, false, {SourceSpec{P + "Denoising Depth", 1}}}}),
    };
    // Radiance mode: the Denoising Data passes follow near-specular bounces
    // (a mirror's albedo, normal and depth are those of what it reflects),
    // which keeps reflections apart in the edge-stopping functions; with a
    // Roughness AOV only on mirrors (rough_guides below).
    p.radiance_mode = {
        spec(ChannelId::Albedo,
             {{{L(P + "Denoising Albedo")}, Convert::None, true}, {{L(P + "DiffCol")}}}),
    };
    p.rough_guides = Preset::RoughGuides{
        P + "Roughness",
        kCyclesMirrorRoughness,
        {
            spec(ChannelId::Albedo, {{{L(P + "DiffCol")}}}),
            spec(ChannelId::Depth, {{{L(P + "Depth")}, Convert::CyclesDepth}}),
        }};
    // Split mode filters only diffuse and glossy: transmission and volume go
    // with what is added back unfiltered, so the output still sums to Combined.
    p.split_mode = {
        spec(ChannelId::Emission, {{{L(P + "Emit"), opt("Env"), times("TransDir", "TransCol", true),
                                     times("TransInd", "TransCol", true), opt("VolumeDir"), opt("VolumeInd")}}}),
    };
    const std::string passes = "View Layer Properties > Passes > ";
    p.settings = {
        {"Combined", passes + "Data > Combined"},
        {"Depth", passes + "Data > Z"},
        {"Normal", passes + "Data > Normal"},
        {"Position", passes + "Data > Position"},
        {"Vector", passes + "Data > Vector (with Render Properties > Motion Blur off)"},
        {"Denoising Albedo", passes + "Data > Denoising Data"},
        {"Denoising Depth", passes + "Data > Denoising Data"},
        {"DiffDir", passes + "Light > Diffuse: Direct"},
        {"DiffInd", passes + "Light > Diffuse: Indirect"},
        {"DiffCol", passes + "Light > Diffuse: Color"},
        {"GlossDir", passes + "Light > Glossy: Direct"},
        {"GlossInd", passes + "Light > Glossy: Indirect"},
        {"GlossCol", passes + "Light > Glossy: Color"},
        {"TransDir", passes + "Light > Transmission: Direct"},
        {"TransInd", passes + "Light > Transmission: Indirect"},
        {"TransCol", passes + "Light > Transmission: Color"},
        {"VolumeDir", passes + "Light > Volume: Direct"},
        {"VolumeInd", passes + "Light > Volume: Indirect"},
        {"Emit", passes + "Light > Other: Emission"},
        {"Env", passes + "Light > Other: Environment"},
        {"Roughness", passes + "Shader AOV: a Value AOV named Roughness, written by an AOV Output node in each material"},
        {"SpecularF0", passes + "Shader AOV: a Color AOV named SpecularF0, written by an AOV Output node in each material"},
    };
    return p;
  }
  throw ChannelMapError("unknown preset '" + name_in + "' (expected dnrender, cycles or auto)");
}

ChannelSpec parse_channel_override(const std::string& assignment, const ChannelSyntax& syntax) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == assignment.size())
    throw ChannelMapError(syntax.map + " expects NAME=SPEC (e.g. albedo=ViewLayer.DiffCol), got '" + assignment + "'");
  const std::string name = trim(assignment.substr(0, eq));
  std::string rhs = trim(assignment.substr(eq + 1));
  const auto* info = protocol::find_channel(name);
  if (!info || info->id == ChannelId::Output) {
    std::string names;
    for (const auto& c : protocol::kChannels)
      if (c.id != ChannelId::Output) names += (names.empty() ? "" : ", ") + std::string(c.name);
    throw ChannelMapError(syntax.map + " " + assignment + ": unknown protocol channel '" + name + "' (one of: " + names +
                          ")");
  }
  RecipeSpec r;
  if (const size_t at = rhs.rfind('@'); at != std::string::npos) {
    const std::string conv = rhs.substr(at + 1);
    rhs = trim(rhs.substr(0, at));
    if (conv != "cycles")
      throw ChannelMapError(syntax.map + " " + assignment + ": unknown conversion '@" + conv + "' (only @cycles)");
    if (info->id == ChannelId::Depth) r.convert = Convert::CyclesDepth;
    else if (info->id == ChannelId::Motion) r.convert = Convert::CyclesVector;
    else throw ChannelMapError(syntax.map + " " + assignment + ": @cycles applies to depth and motion only");
  }
  for (const auto& term : split(rhs, '+')) {
    if (term.empty()) throw ChannelMapError(syntax.map + " " + assignment + ": empty term");
    TermSpec t;
    if (term.find(',') != std::string::npos) {
      t.channels = split(term, ',');
      if (t.channels.size() != info->components)
        throw ChannelMapError(syntax.map + " " + assignment + ": '" + term + "' lists " +
                              std::to_string(t.channels.size()) + " EXR channels, '" + name + "' has " +
                              std::to_string(info->components) + " components");
      for (const auto& c : t.channels)
        if (c.empty()) throw ChannelMapError(syntax.map + " " + assignment + ": empty channel name in '" + term + "'");
    } else {
      t.layer = term;
    }
    r.terms.push_back(std::move(t));
  }
  return ChannelSpec{info->id, {std::move(r)}, true};
}

namespace {

// One term's channels: "layer.{R,G,B}" when they share a layer prefix.
std::string describe_channels(const std::vector<std::string>& t) {
  if (t.size() == 1) return t[0];
  const size_t dot = t[0].rfind('.');
  const std::string pre = dot == std::string::npos ? std::string() : t[0].substr(0, dot + 1);
  bool common = !pre.empty();
  for (const auto& c : t) common = common && c.rfind(pre, 0) == 0 && c.find('.', pre.size()) == std::string::npos;
  std::string out;
  if (common) {
    out += pre + "{";
    for (size_t i = 0; i < t.size(); ++i) out += (i ? "," : "") + t[i].substr(pre.size());
    return out + "}";
  }
  for (size_t i = 0; i < t.size(); ++i) out += (i ? "," : "") + t[i];
  return out;
}

}  // namespace

std::string ResolvedChannel::describe() const {
  std::string out;
  for (size_t i = 0; i < terms.size(); ++i) {
    if (!out.empty()) out += " + ";
    out += describe_channels(terms[i]);
    if (i < factors.size() && !factors[i].empty()) out += " x " + describe_channels(factors[i]);
  }
  if (convert == Convert::CyclesDepth) out += " (Cycles depth)";
  if (convert == Convert::CyclesVector) out += " (Cycles vector)";
  if (convert == Convert::CyclesVirtualDepth) out += " (path length to view depth)";
  if (convert == Convert::CyclesMirrorDirection) out += " (view ray mirrored about it)";
  if (convert == Convert::CyclesChainLength) out += " (path length past the primary hit)";
  if (convert == Convert::CyclesChainDepth) out += " (virtual depth)";
  if (convert == Convert::CyclesCameraNormal) out += " (camera to world)";
  if (convert == Convert::CyclesChainHit) out += " (+ mirror direction x path length past it)";
  return out;
}

bool needs_camera(Convert c) {
  switch (c) {
    case Convert::None:
    case Convert::CyclesDepth:
    case Convert::CyclesVector: return false;
    case Convert::CyclesVirtualDepth:
    case Convert::CyclesMirrorDirection:
    case Convert::CyclesChainLength:
    case Convert::CyclesChainDepth:
    case Convert::CyclesChainHit:
    case Convert::CyclesCameraNormal: return true;
  }
  return true;
}

bool is_derived(Convert c, bool past_specular) { return past_specular || needs_camera(c); }

std::optional<ResolvedChannel> resolve(const ChannelSpec& s, const std::vector<std::string>& chans,
                                       const std::string& prefix, bool plain_only) {
  const uint32_t n = components(s.id);
  for (const auto& alt : s.alternatives) {
    if (plain_only && is_derived(alt.convert, alt.past_specular)) continue;
    ResolvedChannel r{s.id, {}, {}, alt.convert, alt.past_specular, {}};
    bool ok = !alt.terms.empty();
    for (const auto& src : alt.sources) {
      auto found = resolve_term(TermSpec{{}, src.layer, {}, false}, src.components, chans, prefix);
      if (!found) ok = false;
      else r.sources.push_back(std::move(*found));
    }
    for (const auto& t : alt.terms) {
      auto term = resolve_term(t, n, chans, prefix);
      std::optional<std::vector<std::string>> factor;
      if (term && !t.times.empty()) {
        factor = resolve_term(TermSpec{{}, t.times, {}, false}, n, chans, prefix);
        if (!factor) term.reset();
      }
      if (!term) {
        if (t.optional) continue;
        ok = false;
        break;
      }
      r.terms.push_back(std::move(*term));
      r.factors.push_back(factor.value_or(std::vector<std::string>{}));
    }
    if (ok && !r.terms.empty()) return r;
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
        std::string term;
        for (size_t i = 0; i < cands.size(); ++i) term += (i ? "|" : "") + cands[i];
        if (!t.times.empty()) term += " x " + t.times;
        one += t.optional ? "[" + term + "]" : term;
      }
    }
    for (size_t i = 0; i < alt.sources.size(); ++i) one += (i ? ", " : " with ") + alt.sources[i].layer;
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

std::optional<RoughGuidePlan> plan_rough_guides(const Preset& preset, const std::vector<ResolvedChannel>& plan,
                                                const std::vector<std::string>& chans) {
  if (!preset.rough_guides) return std::nullopt;
  const auto& rg = *preset.rough_guides;
  RoughGuidePlan out{resolve(ChannelSpec{ChannelId::Roughness, {{{L(rg.key)}}}}, chans, preset.layer_prefix),
                     rg.from, {}};
  for (const auto& c : plan) {
    if (!c.past_specular) continue;
    for (const auto& s : rg.channels)
      if (s.id == c.id)
        if (auto r = resolve(s, chans, preset.layer_prefix)) out.channels.push_back(std::move(*r));
  }
  const bool has_depth = std::any_of(out.channels.begin(), out.channels.end(),
                                     [](const ResolvedChannel& c) { return c.id == ChannelId::Depth; });
  if (out.channels.empty() || (!out.key && !has_depth)) return std::nullopt;
  return out;
}

std::string RoughGuidePlan::describe_rule() const {
  if (key) {
    char bound[32];
    std::snprintf(bound, sizeof bound, " < %g", double(from));
    return key->describe() + bound;
  }
  return "the Denoising Depth lies beyond Depth";
}

std::vector<ChannelId> parse_channel_list(const std::string& list, const ChannelSyntax& syntax) {
  std::vector<ChannelId> out;
  for (const auto& name : split(list, ',')) {
    const auto* c = protocol::find_channel(name);
    if (!c || c->id == ChannelId::Output)
      throw ChannelMapError(syntax.list + ": unknown protocol channel '" + name + "'");
    if (std::find(out.begin(), out.end(), c->id) != out.end())
      throw ChannelMapError(syntax.list + ": '" + name + "' listed twice");
    out.push_back(c->id);
  }
  return out;
}

namespace {

constexpr ChannelId kStatistics[] = {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3};

bool is_split(ChannelId id) {
  return id == ChannelId::Diffuse || id == ChannelId::Specular || id == ChannelId::DiffuseLighting ||
         id == ChannelId::SpecularLighting || id == ChannelId::SpecularAlbedo;
}

// The renderer settings that make the layers a spec tries ("; in Blender: ...").
std::string settings_hint(const Preset& preset, const ChannelSpec& s) {
  std::vector<std::string> hints;
  std::vector<std::string> layers;
  for (const auto& alt : s.alternatives) {
    for (const auto& t : alt.terms) layers.insert(layers.end(), {t.layer, t.times});
    for (const auto& src : alt.sources) layers.push_back(src.layer);
  }
  for (const std::string& layer : layers)
    for (const auto& [name, where] : preset.settings) {
      const bool match = layer == name || (layer.size() > name.size() &&
                                           layer.compare(layer.size() - name.size(), name.size(), name) == 0 &&
                                           layer[layer.size() - name.size() - 1] == '.');
      if (match && std::find(hints.begin(), hints.end(), where) == hints.end()) hints.push_back(where);
    }
  if (hints.empty()) return {};
  std::string out = "; in Blender turn on ";
  for (size_t i = 0; i < hints.size(); ++i) out += (i ? (i + 1 == hints.size() ? " or " : ", ") : "") + hints[i];
  return out;
}

}  // namespace

std::vector<ResolvedChannel> plan_channels(const Preset& preset, const std::vector<ChannelSpec>& overrides,
                                           const protocol::PipelineInfo* pipeline,
                                           const std::optional<std::vector<ChannelId>>& only,
                                           const std::vector<std::string>& chans, const std::string& file,
                                           const ChannelSyntax& syntax) {
  // The spec used for each channel: an override replaces the preset's, and
  // the preset's mode-specific spec its common one. The mode is known once
  // radiance is decided (radiance_sent below).
  bool radiance_mode = false;
  auto spec_for = [&](ChannelId id) -> std::optional<ChannelSpec> {
    for (const auto& o : overrides)
      if (o.id == id) return o;
    for (const auto& s : radiance_mode ? preset.radiance_mode : preset.split_mode)
      if (s.id == id) return s;
    for (const auto& s : preset.channels)
      if (s.id == id) return s;
    return std::nullopt;
  };
  auto resolvable = [&](ChannelId id) {
    auto s = spec_for(id);
    return s && resolve(*s, chans, preset.layer_prefix, true).has_value();
  };
  auto missing = [&](ChannelId id, const std::string& why) -> ChannelMapError {
    auto s = spec_for(id);
    std::string tried = s ? describe_tried(*s, preset.layer_prefix) : "nothing (no mapping in preset '" + preset.name + "')";
    return ChannelMapError(why + " channel '" + cname(id) + "', but " + file + " has none of the EXR layers tried: " +
                           tried + "; map it with " + syntax.map_example(cname(id)) +
                           (s ? settings_hint(preset, *s) : std::string()));
  };

  std::vector<ChannelId> wanted;
  std::set<ChannelId> must;  // missing -> error
  auto want = [&](ChannelId id, bool required) {
    if (std::find(wanted.begin(), wanted.end(), id) == wanted.end()) wanted.push_back(id);
    if (required) must.insert(id);
  };
  auto wants = [&](ChannelId id) { return std::find(wanted.begin(), wanted.end(), id) != wanted.end(); };
  const std::string pname = pipeline ? "pipeline '" + pipeline->name + "' requires" : "this run needs";

  if (only) {
    for (auto id : *only) want(id, true);
    radiance_mode = wants(ChannelId::Radiance);
  } else {
    for (const auto& o : overrides) want(o.id, true);
    if (pipeline) {
      auto takes = [&](ChannelId id) { return (pipeline->optional_channels & protocol::channel_bit(id)) != 0; };
      for (const auto& c : protocol::kChannels)
        if (pipeline->required_channels & protocol::channel_bit(c.id)) want(c.id, true);
      radiance_mode = wants(ChannelId::Radiance) || (takes(ChannelId::Radiance) && resolvable(ChannelId::Radiance));
      // A pipeline that takes both forms and specular_f0 (auto) gets the split
      // lighting where the file has both signals and F0: what svgf-fb and reflect filter.
      if (radiance_mode && !wants(ChannelId::Radiance) && takes(ChannelId::SpecularF0)) {
        radiance_mode = false;
        const bool split = (resolvable(ChannelId::Diffuse) || resolvable(ChannelId::DiffuseLighting)) &&
                           (resolvable(ChannelId::Specular) || resolvable(ChannelId::SpecularLighting)) &&
                           resolvable(ChannelId::SpecularF0);
        radiance_mode = !split;
      }
      // Split mode: one form per signal, the lighting form where the pipeline
      // takes it and the file has it (with its modulator), unless the
      // radiance form is required or overridden; specular_albedo only as the
      // modulator of specular_lighting.
      const bool diffuse_lighting = !wants(ChannelId::Diffuse) && (wants(ChannelId::DiffuseLighting) ||
                                    (takes(ChannelId::DiffuseLighting) && resolvable(ChannelId::DiffuseLighting)));
      const bool specular_lighting =
          !wants(ChannelId::Specular) &&
          (wants(ChannelId::SpecularLighting) ||
           (takes(ChannelId::SpecularLighting) && resolvable(ChannelId::SpecularLighting) &&
            takes(ChannelId::SpecularAlbedo) && resolvable(ChannelId::SpecularAlbedo)));
      // The sample statistics go all four or none (docs/protocol.md §7.7).
      bool statistics = true;
      for (ChannelId id : kStatistics) statistics = statistics && (wants(id) || (takes(id) && resolvable(id)));
      auto skip = [&](ChannelId id) {
        if (protocol::is_sample_statistic(id)) return !statistics;
        if (const auto field = protocol::sample_field(id)) {
          // Extra samples carry the colour of the session's signals; the
          // lighting forms take none.
          if (diffuse_lighting || specular_lighting) return true;
          if (*field == protocol::SampleField::Radiance) return !radiance_mode;
          if (*field == protocol::SampleField::Diffuse || *field == protocol::SampleField::Specular) return radiance_mode;
          return false;
        }
        if (!is_split(id)) return false;
        if (radiance_mode) return true;
        if (id == ChannelId::Diffuse) return diffuse_lighting;
        if (id == ChannelId::DiffuseLighting) return !diffuse_lighting;
        if (id == ChannelId::Specular) return specular_lighting;
        return !specular_lighting;  // SpecularLighting, SpecularAlbedo
      };
      for (const auto& c : protocol::kChannels) {
        if (!takes(c.id) || skip(c.id)) continue;
        if (resolvable(c.id)) want(c.id, false);
      }
    } else {
      radiance_mode = true;
      for (ChannelId id : {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth,
                           ChannelId::Motion})
        if (resolvable(id)) want(id, id == ChannelId::Radiance);
      if (wanted.empty() || wanted.front() != ChannelId::Radiance) want(ChannelId::Radiance, true);
    }
  }

  std::vector<ResolvedChannel> out;
  for (ChannelId id : wanted) {
    auto s = spec_for(id);
    std::optional<ResolvedChannel> r = s ? resolve(*s, chans, preset.layer_prefix, !must.count(id)) : std::nullopt;
    if (!r) {
      if (must.count(id)) {
        bool overridden = std::any_of(overrides.begin(), overrides.end(), [&](auto& o) { return o.id == id; });
        throw missing(id, overridden ? syntax.map + " maps" : (only ? syntax.list + " lists" : pname));
      }
      continue;
    }
    out.push_back(std::move(*r));
  }
  // Protocol order (by id) keeps the session's declaration stable.
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return uint8_t(a.id) < uint8_t(b.id); });
  return out;
}

bool pipeline_uses_camera(const protocol::PipelineInfo* pipeline) {
  return pipeline && (pipeline->required_channels & protocol::channel_bit(ChannelId::SpecularF0)) != 0;
}

bool plan_needs_camera(const protocol::PipelineInfo* pipeline, const std::vector<ResolvedChannel>& plan) {
  // auto with specular_f0 planned chooses a pipeline that computes F_beta from the view direction.
  const bool auto_with_f0 = pipeline && pipeline->name == protocol::kAutoPipeline &&
                            std::any_of(plan.begin(), plan.end(), [](const ResolvedChannel& c) {
                              return c.id == ChannelId::SpecularF0;
                            });
  return pipeline_uses_camera(pipeline) || auto_with_f0 ||
         std::any_of(plan.begin(), plan.end(), [](const ResolvedChannel& c) { return needs_camera(c.convert); });
}

const ChannelSyntax kCliChannelSyntax{"--channels", "--channel", "--channel NAME=LAYER", "--camera FILE"};
const ChannelSyntax kPythonChannelSyntax{"channels=[...]", "channels={...}", "channels={..., 'NAME': 'LAYER'}",
                                         "camera_file=PATH"};

std::string ChannelSyntax::map_example(const std::string& name, const std::string& layer) const {
  std::string out = example;
  if (const size_t at = out.find("NAME"); at != std::string::npos) out.replace(at, 4, name);
  if (const size_t at = out.find("LAYER"); at != std::string::npos) out.replace(at, 5, layer);
  return out;
}

std::string ChannelSyntax::camera_hint() const {
  return "give the cameras with " + camera + " (examples/blender/export_camera.py writes one)";
}

protocol::Format wire_format(ChannelId id, bool fp16) {
  return fp16 && !protocol::is_sample_statistic(id) ? protocol::Format::F16 : protocol::Format::F32;
}

void convert_cycles_depth(std::span<float> depth) {
  for (float& d : depth)
    if (!(d > 0.0f && d < 1e9f)) d = std::numeric_limits<float>::infinity();
}

void convert_cycles_vector(std::span<float> xy) {
  for (size_t i = 1; i < xy.size(); i += 2) xy[i] = -xy[i];
}

}  // namespace dn::cli
