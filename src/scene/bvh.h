// Bounding volume hierarchy over axis-aligned boxes, built on the host with the surface area
// heuristic and traversed in GLSL and on the CPU (tests) by shaders/shared/intersect.h.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "shared/gpu_types.h"

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

// Builds a binned-SAH BVH over the boxes. maxLeafSize bounds primitives per leaf (the default:
// measured with the node cost, bvh.cpp kTraversalCost).
Bvh buildBvh(const std::vector<Aabb>& boxes, uint32_t maxLeafSize = 8);

// The tree the shaders walk (shared/gpu_types.h BvhNode, shared/intersect.h traceRay): each node
// takes up to four children from the binary tree, expanding the largest inner child first, with
// the children's boxes quantised to bytes (conservatively: the decoded box encloses the child's).
// A walk then visits about half the nodes and loads a node's four boxes in 64 bytes, where the
// binary tree loaded two in 64. Leaves keep their slots; leaves of more than kBvhMaxLeafSize
// primitives are refused (std::invalid_argument). Should the walk's stack (the siblings pending
// along a path) exceed kBvhStackSize, which the binary builder's depth bound does not rule out
// for four children, the nodes take two children each, whose walk needs no more than the depth.
// width (2 to 4) is the children a node takes at most (tests).
std::vector<shader::BvhNode> collapseBvh(const Bvh& bvh, uint32_t width = 4);

// The most entries a walk of these nodes can leave on its stack (the sum, along a path from the
// root, of each node's children but one).
uint32_t bvhStackNeed(const std::vector<shader::BvhNode>& nodes);

}  // namespace telescope
