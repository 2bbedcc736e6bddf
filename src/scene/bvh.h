// Bounding volume hierarchy over axis-aligned boxes, built on the host with the surface area
// heuristic and traversed in GLSL and on the CPU (tests) by shaders/shared/intersect.h.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace telescope {

struct Aabb {
    glm::vec3 lo{1e30f};
    glm::vec3 hi{-1e30f};
    void extend(const glm::vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    void extend(const Aabb& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
    glm::vec3 centre() const { return 0.5f * (lo + hi); }
    float area() const;  // surface area, 0 for an empty box
};

// Node layout shared with the GPU (see shaders/shared/gpu_types.h, struct BvhNode).
// Inner node: count == 0, children at index first and first + 1.
// Leaf: primitives order[first .. first + count).
struct BvhNodeHost {
    glm::vec3 lo; uint32_t first;
    glm::vec3 hi; uint32_t count;
};
static_assert(sizeof(BvhNodeHost) == 32);

struct Bvh {
    // nodes[0] is the root. For no primitives it is the only node: count 0, first 0 and an empty
    // box (lo > hi) that the traversal's box test never enters.
    std::vector<BvhNodeHost> nodes;
    std::vector<uint32_t> order;  // leaf slot -> input primitive index
};

// Builds a binned-SAH BVH over the boxes. maxLeafSize bounds primitives per leaf.
Bvh buildBvh(const std::vector<Aabb>& boxes, uint32_t maxLeafSize = 4);

}  // namespace telescope
