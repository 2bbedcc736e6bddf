// Binned SAH BVH builder (Wald, "On fast construction of SAH-based bounding volume hierarchies",
// 2007): centroids are binned along each axis and the cheapest bin boundary is taken.
#include "scene/bvh.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <stdexcept>
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
// The cost of visiting a node, in units of one primitive test, and (bvh.h) the most primitives a
// leaf holds. A walk on SIMD lanes with masks (lavapipe) pays for a whole node visit, its
// four box tests, sorting network and stack, on every iteration whichever lanes need it, so fewer
// and fuller leaves win. Taking turns, 2026-12-07 (Zen 3 machine; M paths/s, medians of 5-8,
// 256x256, leaf size / node cost): Tungsten's Cornell box (18 primitives) 3.2-3.7 with 4 / 1,
// 3.6-4.9 with 8 / 4; its non-exponential scene (76) 1.17-1.21 -> 1.28-1.41; the water caustic's
// photon passes (103k triangles) the same within noise (photon_trace 6.35-6.91 -> 6.28-7.09 s).
constexpr float kTraversalCost = 4.0f;

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

namespace {

constexpr float kBoxByteMax = 255.0f;

// The float the shaders decode for byte q on an axis: origin + q * scale, where q * scale is exact
// (scale a power of two, q below 256), so a fused multiply-add rounds it the same way.
float decoded(float origin, uint32_t q, float scale) {
    return origin + float(q) * scale;
}

// Quantises the children's [lo, hi] on one axis to bytes from origin in steps of scale, rounding
// outwards; false when a bound needs more than 255 steps.
bool quantiseAxis(const std::vector<Aabb>& boxes, int axis, float origin, float scale, std::vector<uint32_t>& qLo,
                  std::vector<uint32_t>& qHi) {
    for (size_t c = 0; c < boxes.size(); ++c) {
        const float lo = boxes[c].lo[axis], hi = boxes[c].hi[axis];
        // (divided first: the difference of two finite bounds may overflow)
        float steps = std::floor(lo / scale - origin / scale);
        uint32_t q = uint32_t(std::clamp(steps, 0.0f, kBoxByteMax));
        while (q > 0 && decoded(origin, q, scale) > lo) --q;
        if (decoded(origin, q, scale) > lo) return false;
        while (q < 255 && decoded(origin, q + 1, scale) <= lo) ++q;  // (steps below the origin's ulp)
        qLo[c] = q;
        steps = std::ceil(hi / scale - origin / scale);
        if (!(steps <= kBoxByteMax)) return false;
        q = uint32_t(std::max(steps, 0.0f));
        while (q < 255 && decoded(origin, q, scale) < hi) ++q;
        if (decoded(origin, q, scale) < hi) return false;
        while (q > 0 && decoded(origin, q - 1, scale) >= hi) --q;
        qHi[c] = q;
    }
    return true;
}

// One node from the children's references and boxes (at most four; the rest empty).
shader::BvhNode quantiseNode(const std::vector<uint32_t>& refs, const std::vector<Aabb>& boxes) {
    shader::BvhNode node{};
    Aabb all;
    for (const Aabb& b : boxes) all.extend(b);
    glm::vec3 scale(1.0f);
    std::vector<uint32_t> qLo(boxes.size()), qHi(boxes.size());
    std::array<uint32_t, 3> lo{}, hi{};  // four bytes per axis
    for (int axis = 0; axis < 3; ++axis) {
        const float origin = all.lo[axis];
        const float extent = all.hi[axis] - origin;
        if (!std::isfinite(origin) || !std::isfinite(all.hi[axis]))
            throw std::logic_error("BVH bounds not finite (NaN)");
        // The smallest power of two that spans the extent in 255 steps (doubled until rounding
        // fits). Bounds near the float range (an extent that overflows) take 2^127, whose top
        // steps decode to +inf: still enclosing.
        const int exponent = std::isfinite(extent) && extent > 0.0f ? std::ilogb(extent / kBoxByteMax) : 127;
        float s = std::ldexp(1.0f, std::clamp(exponent, -100, 127));
        while (!quantiseAxis(boxes, axis, origin, s, qLo, qHi)) {
            if (s >= 0x1p127f) throw std::logic_error("BVH box quantisation failed");
            s *= 2.0f;
        }
        scale[axis] = s;
        node.origin[axis] = origin;
        for (size_t c = 0; c < boxes.size(); ++c) {
            lo[axis] |= qLo[c] << (8 * c);
            hi[axis] |= qHi[c] << (8 * c);
        }
    }
    // Empty slots: lo byte 255 above hi byte 0 (and kBvhNoChild, which the walk skips)
    for (size_t c = boxes.size(); c < 4; ++c)
        for (int axis = 0; axis < 3; ++axis) lo[axis] |= 255u << (8 * c);
    node.scaleX = scale.x;
    node.scaleYZ = {scale.y, scale.z};
    node.qLo = {lo[0], lo[1], lo[2], hi[0]};
    node.qHi = {hi[1], hi[2]};
    for (size_t c = 0; c < 4; ++c) node.child[c] = c < refs.size() ? refs[c] : shader::kBvhNoChild;
    return node;
}

uint32_t leafRef(const BvhNodeHost& leaf) {
    if (leaf.count > shader::kBvhMaxLeafSize)
        throw std::invalid_argument("a BVH leaf holds more than kBvhMaxLeafSize primitives");
    if (leaf.first >= (1u << 27)) throw std::invalid_argument("more than 2^27 primitives");
    return shader::bvhLeafRef(leaf.first, leaf.count);
}

// Appends the node for the binary node `index` (inner, or the root when it is a leaf) and, depth
// first, those of its inner children; returns its index.
uint32_t collapse(const Bvh& bvh, uint32_t index, size_t width, std::vector<shader::BvhNode>& out) {
    const BvhNodeHost& top = bvh.nodes[index];
    std::vector<uint32_t> kids;
    if (top.count > 0) kids = {index};
    else kids = {top.first, top.first + 1};
    while (kids.size() < width) {
        // Open the inner child of largest area: its children then face the ray's box tests at once
        int best = -1;
        float bestArea = -1.0f;
        for (size_t k = 0; k < kids.size(); ++k) {
            const BvhNodeHost& c = bvh.nodes[kids[k]];
            float area = Aabb{c.lo, c.hi}.area();
            if (c.count == 0 && area > bestArea) {
                best = int(k);
                bestArea = area;
            }
        }
        if (best < 0) break;
        const uint32_t first = bvh.nodes[kids[size_t(best)]].first;
        kids[size_t(best)] = first;
        kids.push_back(first + 1);
    }
    const uint32_t self = uint32_t(out.size());
    out.emplace_back();
    std::vector<uint32_t> refs;
    std::vector<Aabb> boxes;
    for (uint32_t k : kids) {
        const BvhNodeHost& c = bvh.nodes[k];
        refs.push_back(c.count > 0 ? leafRef(c) : collapse(bvh, k, width, out));
        // (bounds beyond the float range hold no finite point: the largest floats enclose them)
        boxes.push_back({glm::max(c.lo, glm::vec3(-FLT_MAX)), glm::min(c.hi, glm::vec3(FLT_MAX))});
    }
    out[self] = quantiseNode(refs, boxes);
    return self;
}

uint32_t stackNeed(const std::vector<shader::BvhNode>& nodes, uint32_t index, uint32_t depth) {
    if (depth > nodes.size()) throw std::invalid_argument("the BVH has a cycle");
    uint32_t children = 0, below = 0;
    for (int c = 0; c < 4; ++c) {
        const uint32_t ref = nodes.at(index).child[c];
        if (ref == shader::kBvhNoChild) continue;
        ++children;
        if (ref < shader::kBvhLeaf) below = std::max(below, stackNeed(nodes, ref, depth + 1));
    }
    return (children > 0 ? children - 1 : 0) + below;
}

}  // namespace

uint32_t bvhStackNeed(const std::vector<shader::BvhNode>& nodes) {
    return nodes.empty() ? 0u : stackNeed(nodes, 0u, 0u);
}

std::vector<shader::BvhNode> collapseBvh(const Bvh& bvh, uint32_t width) {
    std::vector<shader::BvhNode> out;
    if (bvh.order.empty()) {
        out.push_back(quantiseNode({}, {}));  // no children: no ray enters
        return out;
    }
    out.reserve(bvh.nodes.size() / 2 + 1);
    collapse(bvh, 0u, std::clamp(width, 2u, 4u), out);
    if (bvhStackNeed(out) <= shader::kBvhStackSize) return out;
    out.clear();
    collapse(bvh, 0u, 2, out);  // pending entries at most the binary depth, below kBvhStackSize
    return out;
}

}  // namespace telescope
