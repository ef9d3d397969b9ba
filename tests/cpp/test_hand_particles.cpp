// Particle selection among the mesh vertices: determinism, coverage, radius rule.
#include "handsim/hand.h"

#include <gtest/gtest.h>

using namespace handsim;

namespace {
HandModel model(ParticleSampling s, uint64_t seed, int count = 1182, int vertices = 39000) {
  HandDef d;
  d.sampling = s;
  d.seed = seed;
  d.particle_count = count;
  d.render_vertices = vertices;
  return build_hand_model(d);
}
}  // namespace

TEST(HandParticles, SameSeedSameParticlesDifferentSeedDifferent) {
  for (ParticleSampling s : {ParticleSampling::Random, ParticleSampling::Even}) {
    HandModel a = model(s, 7), b = model(s, 7), c = model(s, 8);
    EXPECT_EQ(a.particle_count(), 1182);
    EXPECT_EQ(a.particle_vertex, b.particle_vertex);
    EXPECT_NE(a.particle_vertex, c.particle_vertex);
    for (size_t i = 1; i < a.particle_vertex.size(); ++i) EXPECT_LT(a.particle_vertex[i - 1], a.particle_vertex[i]);
    for (int v : a.particle_vertex) EXPECT_TRUE(a.exposed[v]);  // never buried inside another part
  }
}

TEST(HandParticles, EvenSamplingHasASmallerLargestGap) {
  HandModel r = model(ParticleSampling::Random, 1), e = model(ParticleSampling::Even, 1);
  double gr = largest_particle_gap(r), ge = largest_particle_gap(e);
  std::printf("largest gap: random %.2f mm, even %.2f mm, spacing %.2f mm, radius %.2f mm\n", 1e3 * gr, 1e3 * ge,
              1e3 * r.particle_spacing, 1e3 * r.particle_radius);
  EXPECT_LT(ge, gr);
  EXPECT_LT(ge, r.particle_spacing);  // farthest-point sampling leaves no hole wider than the mean spacing
}

TEST(HandParticles, RadiusRuleAndOverride) {
  HandModel m = model(ParticleSampling::Random, 1);
  EXPECT_NEAR(m.particle_radius, m.particle_spacing / std::sqrt(3.0), 1e-15);
  EXPECT_GT(m.particle_radius, 0.002);
  EXPECT_LT(m.particle_radius, 0.006);
  HandDef d;
  d.particle_radius = 0.004;
  EXPECT_EQ(build_hand_model(d).particle_radius, 0.004);
  d.particle_radius = -1;
  try {
    build_hand_model(d);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "def.particle_radius");
  }
}

TEST(HandParticles, CountIsClampedToTheSkinVertices) {
  HandModel m = model(ParticleSampling::Even, 3, 100000, 2000);
  int exposed = 0;
  for (uint8_t e : m.exposed) exposed += e;
  EXPECT_EQ(m.particle_count(), exposed);
  EXPECT_LT(exposed, m.vertex_count());
}
