// Binned SAH BVH builder (Wald, "On fast construction of SAH-based bounding volume hierarchies",
// 2007): centroids are binned along each axis and the cheapest bin boundary is taken.
#include "scene/bvh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "shared/intersect.h"  // kBvhStackSize: the traversal stack the depth must fit

namespace telescope {

float Aabb::area() const {
    glm::vec3 d = hi - lo;
    if (!(d.x >= 0.0f && d.y >= 0.0f && d.z >= 0.0f)) return 0.0f;
    return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
}

namespace {

constexpr uint32_t kBins = 16;
constexpr float kTraversalCost = 1.0f;  // in units of one primitive test

// Nodes from this depth on split at the object median. Each median split halves the count and
// counts are below 2^32, so no leaf is deeper than kMedianDepth + 32 < kBvhStackSize: the far
// children pending on the traversal stack never exceed the depth.
constexpr uint32_t kMedianDepth = shader::kBvhStackSize - 33u;
static_assert(kMedianDepth + 32u < shader::kBvhStackSize);

// A primitive during the build; the array of these is partitioned in place.
struct Ref {
    Aabb box;
    glm::vec3 centre;
    uint32_t index;
};

// Refs [begin, end) with the union of their boxes and the bounds of their centroids.
struct Range {
    uint32_t begin = 0, end = 0;
    Aabb bounds, centres;
    uint32_t count() const { return end - begin; }
    void add(const Ref& r) {
        bounds.extend(r.box);
        centres.extend(r.centre);
    }
};

struct Task {
    uint32_t node, depth;
    Range range;
};

struct Bin {
    Aabb box;
    uint32_t count = 0;
};

// Half the surface area of a non-empty box (SAH costs only compare areas).
float halfArea(const Aabb& b) {
    glm::vec3 d = b.hi - b.lo;
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

uint32_t binOf(float c, float lo, float scale, uint32_t bins) {
    return std::min(uint32_t((c - lo) * scale), bins - 1);
}

Range makeRange(const std::vector<Ref>& refs, uint32_t begin, uint32_t end) {
    Range r{begin, end, {}, {}};
    for (uint32_t i = begin; i < end; ++i) r.add(refs[i]);
    return r;
}

// Splits r in two: refs for which goesLeft holds first. Both sides' bounds come from the same
// pass.
template <typename Pred>
void partition(std::vector<Ref>& refs, const Range& r, Pred goesLeft, Range& left, Range& right) {
    uint32_t i = r.begin, j = r.end;
    while (i < j) {
        if (goesLeft(refs[i])) {
            left.add(refs[i]);
            ++i;
        } else {
            right.add(refs[i]);
            std::swap(refs[i], refs[--j]);
        }
    }
    left.begin = r.begin;
    left.end = right.begin = i;
    right.end = r.end;
}

// Best binned-SAH split of r. Returns false for a leaf: at most maxLeafSize primitives and no
// split cheaper than testing them all. Without a binnable axis (all centroids equal) a range
// above maxLeafSize is cut in the middle of the list.
bool sahSplit(std::vector<Ref>& refs, const Range& r, uint32_t maxLeafSize, Range& left,
              Range& right) {
    const uint32_t count = r.count();
    const uint32_t bins = std::min(count, kBins);
    std::array<float, 3> scale{};
    for (int axis = 0; axis < 3; ++axis) {
        float extent = r.centres.hi[axis] - r.centres.lo[axis];
        scale[axis] = extent > 0.0f ? float(bins) / extent : 0.0f;
        if (!std::isfinite(scale[axis])) scale[axis] = 0.0f;
    }

    // Bin the centroids along the three axes in one pass
    std::array<std::array<Bin, kBins>, 3> bin;
    for (uint32_t i = r.begin; i < r.end; ++i) {
        const Ref& ref = refs[i];
        for (int axis = 0; axis < 3; ++axis) {
            if (scale[axis] == 0.0f) continue;
            Bin& b = bin[axis][binOf(ref.centre[axis], r.centres.lo[axis], scale[axis], bins)];
            b.box.extend(ref.box);
            ++b.count;
        }
    }

    // Sweep each axis from the right, then from the left: cost of the boundary before bin b
    float bestCost = INFINITY;
    int bestAxis = -1;
    uint32_t bestBin = 0;
    for (int axis = 0; axis < 3; ++axis) {
        if (scale[axis] == 0.0f) continue;
        std::array<float, kBins> rightCost{};
        Aabb box;
        uint32_t n = 0;
        for (uint32_t b = bins - 1; b > 0; --b) {
            box.extend(bin[axis][b].box);
            n += bin[axis][b].count;
            rightCost[b] = n ? halfArea(box) * float(n) : -1.0f;
        }
        box = Aabb{};
        n = 0;
        for (uint32_t b = 1; b < bins; ++b) {
            box.extend(bin[axis][b - 1].box);
            n += bin[axis][b - 1].count;
            if (n == 0 || rightCost[b] < 0.0f) continue;
            float cost = halfArea(box) * float(n) + rightCost[b];
            if (cost < bestCost) {
                bestCost = cost;
                bestAxis = axis;
                bestBin = b;
            }
        }
    }

    if (bestAxis < 0) {
        if (count <= maxLeafSize) return false;
        uint32_t mid = r.begin + count / 2;
        left = makeRange(refs, r.begin, mid);
        right = makeRange(refs, mid, r.end);
        return true;
    }

    // Costs relative to the parent's area: leaf = A N, split = A C_trav + A_l N_l + A_r N_r
    float area = halfArea(r.bounds);
    if (count <= maxLeafSize && area * float(count) <= area * kTraversalCost + bestCost) return false;

    const float lo = r.centres.lo[bestAxis], s = scale[bestAxis];
    partition(refs, r, [&](const Ref& ref) { return binOf(ref.centre[bestAxis], lo, s, bins) < bestBin; },
              left, right);
    return true;
}

// Object-median split along the widest centroid axis (the middle of the list if none); false
// for a leaf.
bool medianSplit(std::vector<Ref>& refs, const Range& r, uint32_t maxLeafSize, Range& left,
                 Range& right) {
    if (r.count() <= maxLeafSize) return false;
    uint32_t mid = r.begin + r.count() / 2;
    glm::vec3 extent = r.centres.hi - r.centres.lo;
    int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    if (extent[axis] > 0.0f) {
        std::nth_element(refs.begin() + r.begin, refs.begin() + mid, refs.begin() + r.end,
                         [axis](const Ref& a, const Ref& b) { return a.centre[axis] < b.centre[axis]; });
    }
    left = makeRange(refs, r.begin, mid);
    right = makeRange(refs, mid, r.end);
    return true;
}

// Node boxes are widened by one ulp: a ray lying in a face plane of its primitives' bounds
// (a zero direction component, origin on the plane) is then strictly inside the slab, where the
// slab test with a huge finite reciprocal (shaders/shared/intersect.h) is exact.
glm::vec3 widen(glm::vec3 p, float towards) {
    return {std::nextafter(p.x, towards), std::nextafter(p.y, towards), std::nextafter(p.z, towards)};
}

}  // namespace

Bvh buildBvh(const std::vector<Aabb>& boxes, uint32_t maxLeafSize) {
    Bvh bvh;
    maxLeafSize = std::max(maxLeafSize, 1u);
    const uint32_t n = uint32_t(boxes.size());

    // No primitives: the root has count 0 and an empty box, which no ray enters
    if (n == 0) {
        Aabb empty;
        bvh.nodes.push_back({empty.lo, 0u, empty.hi, 0u});
        return bvh;
    }

    std::vector<Ref> refs(n);
    for (uint32_t i = 0; i < n; ++i) refs[i] = {boxes[i], boxes[i].centre(), i};
    bvh.nodes.reserve(2 * size_t(n) - 1);
    bvh.nodes.push_back({});

    // Split top-down, depth first; the two children of a node are allocated together
    std::vector<Task> tasks{{0u, 0u, makeRange(refs, 0, n)}};
    while (!tasks.empty()) {
        Task task = tasks.back();
        tasks.pop_back();
        const Range& r = task.range;
        Range left, right;
        bool split = false;
        if (r.count() > 1) {
            split = task.depth < kMedianDepth ? sahSplit(refs, r, maxLeafSize, left, right)
                                              : medianSplit(refs, r, maxLeafSize, left, right);
        }

        BvhNodeHost& node = bvh.nodes[task.node];
        node.lo = widen(r.bounds.lo, -INFINITY);
        node.hi = widen(r.bounds.hi, INFINITY);
        if (!split) {
            node.first = r.begin;
            node.count = r.count();
            continue;
        }
        const uint32_t child = uint32_t(bvh.nodes.size());
        node.first = child;
        node.count = 0;
        bvh.nodes.push_back({});
        bvh.nodes.push_back({});
        tasks.push_back({child + 1, task.depth + 1, right});
        tasks.push_back({child, task.depth + 1, left});
    }

    bvh.order.resize(n);
    for (uint32_t i = 0; i < n; ++i) bvh.order[i] = refs[i].index;
    return bvh;
}

}  // namespace telescope
