#include "integrator.hpp"

#include <algorithm>

#include "bsdf.hpp"

namespace dn::render {
namespace {

float max_component(const glm::vec3& v) { return std::max({v.x, v.y, v.z}); }

constexpr int kRouletteDepth = 1;  // bounces before Russian roulette may end a path

}  // namespace

PathResult trace_path(const Scene& scene, const glm::vec3& dir, const Hit& primary, Rng& rng,
                      const PathSettings& settings, TraceContext& ctx) {
  PathResult r;
  if (!primary.found) {
    r.emission = scene.environment();
    return r;
  }
  r.emission = scene.emitted(primary, dir);

  Hit hit = primary;
  glm::vec3 wo_world = -dir;
  glm::vec3 throughput(1.0f);
  Lobe first_lobe = Lobe::Diffuse;
  auto gather = [&](const glm::vec3& c) { (first_lobe == Lobe::Diffuse ? r.diffuse : r.specular) += c; };

  for (int depth = 0; depth < settings.max_depth; ++depth) {
    const Material& material = scene.material_of(hit);
    if (material.kind == MaterialKind::Emitter) break;
    const SurfaceParams surface = evaluate_material(material, hit.position);
    const glm::vec3 n = facing_normal(hit.normal, wo_world);
    const Frame frame(n);
    const Bsdf bsdf(surface, frame.to_local(wo_world));

    // Next-event estimation: one light, chosen by power.
    if (settings.next_event && scene.has_lights()) {
      const float u_select = rng.next();
      const LightSample ls = scene.sample_light(hit.position, u_select, rng.next2());
      const glm::vec3 wi = frame.to_local(ls.wi);
      if (ls.valid && wi.z > 0.0f) {
        const BsdfEval e = bsdf.eval(wi);
        glm::vec3 cd = e.f_diffuse * (wi.z * (ls.delta ? 1.0f : power_heuristic(ls.pdf, e.pdf_diffuse) / ls.pdf));
        glm::vec3 cs = e.f_specular * (wi.z * (ls.delta ? 1.0f : power_heuristic(ls.pdf, e.pdf_specular) / ls.pdf));
        cd *= throughput * ls.radiance;
        cs *= throughput * ls.radiance;
        if (max_component(cd + cs) > 0.0f &&
            !scene.occluded(offset_origin(hit.position, n, ls.wi), ls.wi, ls.distance * 0.999f, ctx)) {
          if (depth == 0) {
            r.diffuse += cd;
            r.specular += cs;
          } else {
            gather(cd + cs);
          }
        }
      }
    }

    // Continue the path by sampling one lobe.
    const float u_lobe = rng.next();
    const BsdfSample bs = bsdf.sample(u_lobe, rng.next2());
    if (!bs.valid) break;
    if (depth == 0) first_lobe = bs.lobe;
    throughput *= bs.weight;
    const glm::vec3 wi_world = glm::normalize(frame.to_world(bs.wi));
    const Hit next = scene.intersect(offset_origin(hit.position, n, wi_world), wi_world, ctx);
    if (!next.found) {
      gather(throughput * scene.environment());
      break;
    }
    const glm::vec3 le = scene.emitted(next, wi_world);
    if (max_component(le) > 0.0f) {
      const int light = scene.light_of(next);
      const float w = light >= 0 && settings.next_event ? power_heuristic(bs.pdf, scene.light_pdf(light, hit.position, next)) : 1.0f;
      gather(throughput * le * w);
    }
    hit = next;
    wo_world = -wi_world;
    if (depth >= kRouletteDepth) {
      const float q = std::min(0.95f, max_component(throughput));
      if (rng.next() >= q) break;
      throughput /= q;
    }
  }
  return r;
}

}  // namespace dn::render
