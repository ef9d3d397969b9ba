// The procedural hand surface: a palm slab and five tubes, each a closed surface of stitched vertex rings.
#pragma once

#include "handsim/hand.h"

#include <cstdint>
#include <vector>

namespace handsim {

struct ProceduralHandMesh {
  SkinnedMesh mesh;
  std::vector<uint8_t> exposed;  // 0: the vertex lies inside another part (hidden, never a particle)
};

// Deterministic: the same bind frame and target give the same mesh.
ProceduralHandMesh build_procedural_hand_mesh(const HandFrame& bind, int target_vertices);

}  // namespace handsim
