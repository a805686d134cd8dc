// Channel maps: which EXR channels make each protocol channel, for the
// example renderer's own layout ("dnrender") and Blender Cycles multilayer
// EXRs ("cycles"), plus user overrides (--channel NAME=SPEC) and the Cycles
// depth/vector conversions. docs/client.md documents every mapping.
#pragma once

#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/protocol/channels.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::cli {

// Missing or unresolvable channels; what() names the channel and what was tried.
class ChannelMapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Convert {
  None,
  CyclesDepth,   // Depth.Z: view-axis distance; background 1e10 -> +inf
  CyclesVector,  // Vector.XY: (p_prev - p) in raster space, +y up -> PixelsToPrevious, y down
  CyclesVirtualDepth,  // Denoising Depth: length of the path to the first non-specular hit -> that point's depth
                       // along the pixel's view ray (x cos of the ray's angle to the view axis; needs the frame's
                       // projection); background (FLT_MAX) -> +inf
  // The reflection features of a renderer without them (reflection_features.hpp), from the frame's camera:
  CyclesMirrorDirection,  // Normal: the pixel's view ray reflected about it
  CyclesChainLength,      // Denoising Depth: the path's length past the primary hit
  CyclesChainDepth,       // Denoising Depth: the virtual depth (primary + that length, as a view depth)
  CyclesChainHit,         // Position: + mirror direction x that length
  CyclesCameraNormal,     // Denoising Normal: camera space -> world
};

// One summand: either explicit EXR channels (one per component) or a layer
// whose component channels are found in the file (LAYER.R/G/B, LAYER.X/Y/Z, ...),
// optionally multiplied component-wise by another layer (Cycles' lighting
// passes times their colour pass: TransDir x TransCol).
struct TermSpec {
  std::vector<std::string> channels;  // explicit
  std::string layer;                  // or a layer name
  std::string times;                  // a layer to multiply by (empty: none)
  bool optional = false;              // left out when the file lacks it (the others still make the channel)
};
// A layer a conversion reads besides its terms: the recipe applies only
// when the file has it.
struct SourceSpec {
  std::string layer;
  uint32_t components = 1;
};
// One way to make a channel: the sum of its terms, then a conversion.
struct RecipeSpec {
  std::vector<TermSpec> terms;
  Convert convert = Convert::None;
  // Cycles' Denoising Data passes: they describe the first non-specular hit
  // of the path, which Preset::rough_guides replaces where the surface is not
  // a mirror.
  bool past_specular = false;
  std::vector<SourceSpec> sources;
};

// True for the conversions the client computes with the frame's camera.
bool needs_camera(Convert convert);
// A derived recipe: made with the camera or a mirror guide (past_specular).
// Only a channel the pipeline requires is made by one; a channel it merely
// accepts is sent as the file has it, or not at all.
bool is_derived(Convert convert, bool past_specular);
// All ways to make a protocol channel, tried in order.
struct ChannelSpec {
  protocol::ChannelId id = protocol::ChannelId::Radiance;
  std::vector<RecipeSpec> alternatives;
  bool user = false;  // from --channel: always sent
};

struct Preset {
  std::string name;  // "dnrender" or "cycles"
  std::string layer_prefix;  // cycles: detected view layer, e.g. "ViewLayer"
  std::vector<ChannelSpec> channels;
  // Replace a channel's spec when radiance is sent (radiance mode) or not
  // (split mode): Cycles guides radiance with the Denoising Data passes, and
  // its split mode needs the colour of the lighting passes it does not filter.
  std::vector<ChannelSpec> radiance_mode, split_mode;
  // Where a missing layer is turned on in the renderer, by layer name
  // ("DiffCol" -> "View Layer Properties > Passes > Light > Diffuse: Color").
  std::vector<std::pair<std::string, std::string>> settings;
  // Per-pixel guides (Cycles radiance mode): the past_specular recipes are
  // exact only on perfect mirrors; on a glossy surface at 1 spp they describe
  // one random reflection. Where the pixel's `key` layer (a Roughness AOV) is
  // at or above `from`, or not finite, the guide channel takes its recipe
  // from `channels` (the primary hit's) instead.
  struct RoughGuides {
    std::string key;
    float from = 0.0f;
    std::vector<ChannelSpec> channels;
  };
  std::optional<RoughGuides> rough_guides;
};

// Surfaces with a Roughness AOV below this are mirrors, whose Denoising Data
// guides are exact at 1 spp (docs/client.md, "Mirrors and the Denoising Data
// passes": on the bench scene 0.02 and 0.1 measure alike; 0.3 takes in the
// gold sphere, roughness 0.2, and svgf's relMSE rises 2.6x).
inline constexpr float kCyclesMirrorRoughness = 0.02f;
// Without a Roughness AOV: a pixel's path went past its primary hit when the
// Denoising Depth, as a view depth, exceeds Depth by more than this fraction
// (where the path stops they agree to <= 1 % at 1 spp: the sample is not at
// the pixel centre; CyclesFixtures.VirtualDepthIsTheViewDepth...).
inline constexpr float kPastPrimaryDepth = 0.02f;
// Below this in every component an albedo is no reflectance (the server's DN_ALBEDO_MIN).
inline constexpr float kReflectanceMin = 1e-3f;

// The preset for `name` ("dnrender", "cycles" or "auto": cycles when the file
// has a "<layer>.Combined.R" channel). `view_layer` overrides the Cycles view
// layer detection. Throws ChannelMapError for an unknown name.
Preset make_preset(const std::string& name, const std::vector<std::string>& exr_channels,
                   const std::string& view_layer = {});

// How the caller's interface names its input choices, for error messages:
// `dn denoise`'s options or dn.read_frame's keywords.
struct ChannelSyntax {
  std::string list;  // the exact channel list: "--channels"
  std::string map;   // one mapping: "--channel"
  std::string example;  // mapping channel NAME by hand: "--channel NAME=LAYER"
  std::string camera;   // a file of the frames' cameras: "--camera FILE"
  // `example` for channel `name` from `layer`.
  std::string map_example(const std::string& name, const std::string& layer = "LAYER") const;
  // "give the cameras with --camera FILE (... writes one)".
  std::string camera_hint() const;
};
extern const ChannelSyntax kCliChannelSyntax;     // --channels LIST, --channel NAME=SPEC
extern const ChannelSyntax kPythonChannelSyntax;  // channels=[...], channels={NAME: SPEC}

// Parses "--channel NAME=SPEC". SPEC: terms joined by '+'; a term is a layer
// name (DiffCol, ViewLayer.DiffCol) or explicit channels separated by ','
// (N.X,N.Y,N.Z). A trailing "@cycles" applies the Cycles conversion (depth,
// motion). Throws ChannelMapError on syntax errors, worded in `syntax`.
ChannelSpec parse_channel_override(const std::string& assignment, const ChannelSyntax& syntax = kCliChannelSyntax);

// A concrete recipe: per term, one EXR channel name per component, and per
// term the channels of its factor (empty: none).
struct ResolvedChannel {
  protocol::ChannelId id = protocol::ChannelId::Radiance;
  std::vector<std::vector<std::string>> terms;
  std::vector<std::vector<std::string>> factors;  // one per term
  Convert convert = Convert::None;
  bool past_specular = false;  // from a RecipeSpec with past_specular
  std::vector<std::vector<std::string>> sources;  // the RecipeSpec's sources, one EXR channel per component
  std::string describe() const;  // "ViewLayer.DiffDir.{R,G,B} + ViewLayer.DiffInd.{R,G,B}"
};

// First alternative whose channels and sources all exist in `exr_channels`;
// with `plain_only`, derived alternatives (is_derived) are skipped.
std::optional<ResolvedChannel> resolve(const ChannelSpec& spec, const std::vector<std::string>& exr_channels,
                                       const std::string& layer_prefix, bool plain_only = false);
// The layers an alternative list tries, for error messages ("ViewLayer.DiffCol, DiffCol").
std::string describe_tried(const ChannelSpec& spec, const std::string& layer_prefix);

// Decides what to send: every channel the pipeline requires (error naming the
// channel and the layers tried when one is missing), every --channel override,
// and the pipeline's optional channels the file has. The split-radiance
// channels (diffuse, specular) are left out when radiance is sent, unless
// required or overridden; the sample statistics (51-54) are taken as
// optional channels only all four together. `only` (from --channels) replaces the automatic
// choice. `pipeline` may be null (server did not list it): then `only` or the
// overrides, else radiance/albedo/normal/depth/motion when present. Only the
// required, listed and overridden channels take derived recipes (is_derived);
// the others take the file's plain layers. Errors are worded in `syntax`.
std::vector<ResolvedChannel> plan_channels(const Preset& preset, const std::vector<ChannelSpec>& overrides,
                                           const protocol::PipelineInfo* pipeline,
                                           const std::optional<std::vector<protocol::ChannelId>>& only,
                                           const std::vector<std::string>& exr_channels, const std::string& file,
                                           const ChannelSyntax& syntax = kCliChannelSyntax);

// True when the server's passes use the frame's camera: a pipeline that
// requires specular_f0 computes F_beta from the view direction; the others
// run with identity matrices.
bool pipeline_uses_camera(const protocol::PipelineInfo* pipeline);
// True when a run needs each frame's camera: the pipeline uses it, a
// planned channel is converted with it, or auto gets specular_f0.
bool plan_needs_camera(const protocol::PipelineInfo* pipeline, const std::vector<ResolvedChannel>& plan);

// Preset::rough_guides resolved for a plan: for each planned channel taken
// past_specular, the recipe that replaces it on pixels that are not mirrors,
// and how a mirror is told: by the key layer (as a roughness channel) below
// `from`, or, when the file has no key layer, by the path going past the
// primary hit (the past_specular depth beyond the primary depth by more than
// kPastPrimaryDepth; that needs depth among the channels). Empty when the
// preset has none, no planned channel is past_specular, or neither way
// applies.
struct RoughGuidePlan {
  std::optional<ResolvedChannel> key;
  float from = 0.0f;
  std::vector<ResolvedChannel> channels;
  std::string describe_rule() const;  // "ViewLayer.Roughness.X < 0.02", or the depth rule
};
std::optional<RoughGuidePlan> plan_rough_guides(const Preset& preset, const std::vector<ResolvedChannel>& plan,
                                                const std::vector<std::string>& exr_channels);

// The format a channel is declared in: F16 with --fp16, except the sample
// statistics (ids 51-54), which the protocol takes in F32 only
// (docs/protocol.md §7.7; an F16 one is refused, INVALID_CHANNEL).
protocol::Format wire_format(protocol::ChannelId id, bool fp16);

// Parses "radiance,albedo,..." (protocol channel names); errors worded in `syntax`.
std::vector<protocol::ChannelId> parse_channel_list(const std::string& list,
                                                   const ChannelSyntax& syntax = kCliChannelSyntax);

// Cycles conversions, in place on interleaved data.
// Depth: values >= 1e9 or <= 0 (Cycles' background: Depth 1e10, Denoising Depth 0) and non-finite become +inf.
void convert_cycles_depth(std::span<float> depth);
// Vector: xy = (V.x, -V.y), in place on 2-component data.
void convert_cycles_vector(std::span<float> xy);

}  // namespace dn::cli
