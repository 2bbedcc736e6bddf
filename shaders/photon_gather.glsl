// The photon-map lookups (GLSL only; after the PhotonMapRef declarations). Fixed radius: ONE
// traversal of the 2x2x2 cells around x accumulates, from the same photons, the kernel sum at r_b and the
// closed-form difference K_{r'} - K_r (shared/photon_density.h). Photons arriving from behind
// the surface (dot(w_i, n) <= 0) are rejected, unless the includer's PHOTON_BOTH_SIDES says the
// gather vertex takes both sides (gather.comp: a rough dielectric, whose BSDF transmits them).
//
// Lavapipe ends the loops of a shader invocation after 65535 iterations in all, without a word,
// and a bucket may hold millions of photons. One call therefore reads photons sliceBegin ..
// sliceBegin + kGatherSlicePhotons - 1 of each bucket (at most 8 x 4096 iterations); the caller
// runs as many slices (dispatches) as the fullest bucket needs (PhotonMapHeader::maxBucket) and
// adds their sums.
//
// The sorted photons are read as texels of 4 x uint32 (photon i is texels 2i and 2i + 1) through
// a uniform texel buffer, which the including shader declares as `sortedTexels`. Lavapipe fetches
// a divergent texel with vector loads, where a divergent load from a storage buffer or an address
// loops over the lanes once per component: the gather is 2.8x faster (docs/BENCHMARKS.photon-notes.md).
// A sorted array larger than the device lets a texel buffer be is read by address instead: a
// pipeline of its own (kSpecSortedTexels = 0), since a choice made at run time in the loop cost
// the texels' whole gain.
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Uvec4ArrayRef { uvec4 v[]; };

uvec4 sortedTexel(Uvec4ArrayRef sorted, uint t) {
    return kSortedTexels ? texelFetch(sortedTexels, int(t)) : sorted.v[t];
}

// The BSDF factor of a photon arriving from direction w (towards where it came from) at the gather
// vertex, divided by the cosine its flux already carries: the includer may define PHOTON_BSDF(w)
// (gather.comp: the glossy materials of shared/bsdf.h); by default 1, for a Lambertian vertex
// whose constant f the caller multiplies the sums by.
#ifndef PHOTON_BSDF
#define PHOTON_BSDF(w) vec3(1.0)
#endif
#ifndef PHOTON_BOTH_SIDES
#define PHOTON_BOTH_SIDES false
#endif

struct GatherSums {
    vec3 base;        // sum Phi_i W_{r_b}
    vec3 difference;  // sum Phi_i (W_{r'} - W_r)
    uint found;       // photons within r_b on the front side
};

// Whether no point of cell is nearer to x than sqrt(bound2): then no photon there can count and
// its bucket is not read. The distance is shortened by a margin above the rounding of the cell's
// bounds and of the photons' cell assignment, so the skip is exact; border cells (which gather
// every point beyond them) are never skipped.
bool cellBeyond(PhotonMapRef map, ivec3 cell, vec3 x, float bound2) {
    float size = map.h.cellSize;
    vec3 lo = vec3(cell) * size;
    vec3 ax = abs(x);
    float margin = 1e-6 * (max(ax.x, max(ax.y, ax.z)) + size);
    vec3 away = max(max(lo - x, x - (lo + size)) - margin, vec3(0.0));
    bool inside = all(lessThan(abs(vec3(cell)), vec3(kGridCellLimit - 1.0)));
    return inside && dot(away, away) >= bound2;
}

// The photons [first, last) of bucket h that a slice starting at sliceBegin reads, at most
// sliceLength; more is set when the bucket holds photons beyond this slice. A query reads each
// bucket once: the cells around x (2x2x2, or 5x5x5 for k nearest) lie within 8 of each other on
// every axis, where gridHash gives distinct buckets (shared/photon_density.h), and a photon of
// another cell in a bucket read lies 8 cells away at least, beyond r_b.
void bucketSlice(PhotonMapRef map, uint h, uint sliceBegin, uint sliceLength, out uint first, out uint last,
                 inout bool more) {
    UintArrayRef cellStart = UintArrayRef(uvec2(map.h.cellStartLo, map.h.cellStartHi));
    // The scatter left the end of bucket h's range in cellStart[h], so bucket h - 1's end is
    // where h begins (hash_grid_build.comp).
    uint begin = h == 0u ? 0u : cellStart.v[h - 1u];
    uint count = cellStart.v[h] - begin;
    more = more || count - min(count, sliceBegin) > sliceLength;
    first = begin + min(sliceBegin, count);
    last = begin + min(count, sliceBegin + sliceLength);
}

// rb2 = r_b^2; logRadius2 = ln(r^2 / r_b^2), logStep2 = ln(r'^2 / r^2); no difference when
// difference is false. Photons stored at a light-path vertex beyond maxVertex are left out (the
// full path would have more scattering vertices than max_bounces allows: photon_trace.comp).
// more: whether a later slice has photons for x.
GatherSums gatherPhotons(PhotonMapRef map, vec3 x, vec3 n, float rb2, bool difference, float logRadius2,
                         float logStep2, uint kernel, uint sliceBegin, uint maxVertex, out bool more) {
    GatherSums s;
    s.base = vec3(0.0);
    s.difference = vec3(0.0);
    s.found = 0u;
    Uvec4ArrayRef sorted = Uvec4ArrayRef(uvec2(map.h.sortedLo, map.h.sortedHi));
    float rj2 = rb2 * exp(logRadius2);

    ivec3 low = gridNeighbourhood(x, map.h.cellSize);
    more = false;
    for (uint c = 0u; c < 8u; ++c) {
        ivec3 cell = low + ivec3(int(c & 1u), int((c >> 1u) & 1u), int(c >> 2u));
        if (cellBeyond(map, cell, x, rb2)) continue;
        uint first, last;
        bucketSlice(map, gridHash(cell, map.h.tableSize), sliceBegin, kGatherSliceLength, first, last, more);
        for (uint i = first; i < last; ++i) {
            // The position first: most photons of the cells lie beyond r_b, and the rest of the
            // photon is read only for those within (measured 7% faster than reading it whole).
            uvec4 position = sortedTexel(sorted, 2u * i);
            vec3 d = x - uintBitsToFloat(position.xyz);
            float d2 = dot(d, d);
            if (!(d2 < rb2) || position.w > maxVertex) continue;
            uvec4 rest = sortedTexel(sorted, 2u * i + 1u);  // power, direction
            vec3 w = decodeDirection(rest.w);
            if (dot(w, n) <= 0.0 && !PHOTON_BOTH_SIDES) continue;
            vec3 power = uintBitsToFloat(rest.xyz) * PHOTON_BSDF(w);
            s.found += 1u;
            s.base += power * kernelWeight(kernel, d2, rb2);
            if (difference && d2 < rj2) s.difference += power * kernelDifference(kernel, d2, rj2, logStep2);
        }
    }
    return s;
}

// ---- k nearest photons within r_b (Tungsten's gather_photon_count) ----
// Tungsten's gather takes the k photons nearest to x (of any direction) within the gather radius;
// its radius is then the k-th distance r_k when it found k, else r_b, and the estimate is
// sum_i f Phi_i W_{r}(|x - x_i|) over those photons (uniform kernel: 1 / (pi r^2) each; the
// k-th photon sits on the kernel's edge and counts). The search keeps the k smallest squared
// distances and their photons' sorted indices in k slots, empty ones at +inf (kInfinity), and the
// slot of the largest: a photon nearer than it takes its slot, and the largest is found again, so
// filling and replacing are one operation. A gather in several slices carries the slots in memory
// between them (nearestStore / nearestLoad: two slots a uvec4). Slices read gatherSlicePhotons(k)
// photons of each bucket (lavapipe's loop budget: gpu_types.h).
layout(buffer_reference, std430, buffer_reference_align = 16) buffer NearestStateRef { uvec4 v[]; };

// The slots are arrays of the spec constant's length, and every loop over them runs over all of
// them and asks to be unrolled ([[unroll]], which Mesa's NIR honours whatever the trip count), so
// the slots live in registers and the loops add no iterations to lavapipe's loop cap. (A max-heap
// indexed at run time kept them in memory that lavapipe reads and writes one lane at a time: the
// k-nearest gather took 9x as long; docs/BENCHMARKS.md.)
const uint kNearestSlots = kGatherCount == 0u ? 1u : kGatherCount;
struct NearestPhotons {
    float d2[kNearestSlots];
    uint index[kNearestSlots];
    float farthest;     // the largest d2 kept: the bound (kInfinity while a slot is empty)
    uint farthestSlot;  // its slot
};

// The farthest kept again after a slot changed.
void nearestFindFarthest(inout NearestPhotons s) {
    s.farthest = s.d2[0];
    s.farthestSlot = 0u;
    [[unroll]] for (uint j = 1u; j < kNearestSlots; ++j) {
        if (s.d2[j] > s.farthest) {
            s.farthest = s.d2[j];
            s.farthestSlot = j;
        }
    }
}

void nearestClear(inout NearestPhotons s) {
    [[unroll]] for (uint j = 0u; j < kNearestSlots; ++j) {
        s.d2[j] = kInfinity;
        s.index[j] = 0u;
    }
    s.farthest = kInfinity;
    s.farthestSlot = 0u;
}

// Replaces the farthest photon kept by one at squared distance d2 (nearer than it).
void nearestReplaceFarthest(inout NearestPhotons s, float d2, uint index) {
    [[unroll]] for (uint j = 0u; j < kNearestSlots; ++j) {
        if (j == s.farthestSlot) {
            s.d2[j] = d2;
            s.index[j] = index;
        }
    }
    nearestFindFarthest(s);
}

// Photons sliceBegin .. sliceBegin + kGatherSliceLength - 1 of the bucket of each cell around x
// offered to the k nearest kept in s; more: whether a later slice has photons for x.
// Cells of side r_b / m (m = kNearestCellsPerRadius, the host's PhotonMap cell size for k-nearest
// gathers): every photon within r_b of x lies in the (2m + 1)^3 cells around x's own. Its own cell
// first, then the others: once the k nearest of its own cell are in, the bound (the farthest kept)
// skips every cell no nearer photon can lie in, which in a crowded caustic is all of them, so a
// pixel there reads the photons of one cell of side r_b / 2 (docs/PHOTON-MAPPING.md "k nearest").
void nearestSearch(PhotonMapRef map, vec3 x, float rb2, uint sliceBegin, inout NearestPhotons s, out bool more) {
    Uvec4ArrayRef sorted = Uvec4ArrayRef(uvec2(map.h.sortedLo, map.h.sortedHi));
    ivec3 own = gridCell(x, map.h.cellSize);
    const int m = int(kNearestCellsPerRadius), n = int(kNearestCellsPerAxis);
    const uint centre = kNearestCells / 2u;  // the offset (0, 0, 0)
    more = false;
    for (uint j = 0u; j < kNearestCells; ++j) {
        uint c = j == 0u ? centre : (j <= centre ? j - 1u : j);
        ivec3 cell = own + ivec3(int(c) % n - m, (int(c) / n) % n - m, int(c) / (n * n) - m);
        if (cellBeyond(map, cell, x, min(rb2, s.farthest))) continue;
        uint first, last;
        bucketSlice(map, gridHash(cell, map.h.tableSize), sliceBegin, kGatherSliceLength, first, last, more);
        for (uint i = first; i < last; ++i) {
            vec3 d = x - uintBitsToFloat(sortedTexel(sorted, 2u * i).xyz);
            float d2 = dot(d, d);
            if (d2 < rb2 && d2 < s.farthest) nearestReplaceFarthest(s, d2, i);
        }
    }
}

// The estimate over the k nearest: kernel radius r_k^2 (the farthest kept) when all k slots are
// full, else r_b^2; photons arriving from behind the surface (at a vertex that does not take both
// sides), or stored beyond maxVertex, add nothing but count among the k, as in Tungsten.
GatherSums nearestSums(PhotonMapRef map, NearestPhotons s, vec3 n, float rb2, uint kernel, uint maxVertex) {
    GatherSums g;
    g.base = vec3(0.0);
    g.difference = vec3(0.0);
    g.found = 0u;
    Uvec4ArrayRef sorted = Uvec4ArrayRef(uvec2(map.h.sortedLo, map.h.sortedHi));
    float r2 = s.farthest < kInfinity ? s.farthest : rb2;
    [[unroll]] for (uint j = 0u; j < kNearestSlots; ++j) {
        if (!(s.d2[j] < kInfinity)) continue;
        uvec4 rest = sortedTexel(sorted, 2u * s.index[j] + 1u);
        g.found += 1u;
        vec3 w = decodeDirection(rest.w);
        if ((dot(w, n) <= 0.0 && !PHOTON_BOTH_SIDES) || sortedTexel(sorted, 2u * s.index[j]).w > maxVertex) continue;
        g.base += uintBitsToFloat(rest.xyz) * PHOTON_BSDF(w) * nearestKernelWeight(kernel, s.d2[j], r2);
    }
    return g;
}

// The k nearest so far across slices: two slots a uvec4.
void nearestStore(NearestStateRef state, uint at, NearestPhotons s) {
    [[unroll]] for (uint j = 0u; j < kNearestSlots; j += 2u) {
        uint j1 = min(j + 1u, kNearestSlots - 1u);
        state.v[at + j / 2u] = uvec4(floatBitsToUint(s.d2[j]), s.index[j], floatBitsToUint(s.d2[j1]), s.index[j1]);
    }
}

void nearestLoad(NearestStateRef state, uint at, inout NearestPhotons s) {
    [[unroll]] for (uint j = 0u; j < kNearestSlots; j += 2u) {
        uvec4 v = state.v[at + j / 2u];
        s.d2[j] = uintBitsToFloat(v.x);
        s.index[j] = v.y;
        if (j + 1u < kNearestSlots) {
            s.d2[j + 1u] = uintBitsToFloat(v.z);
            s.index[j + 1u] = v.w;
        }
    }
    nearestFindFarthest(s);
}
