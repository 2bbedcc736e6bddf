// The photon-map lookup (GLSL only; after the PhotonMapRef declarations): ONE traversal of the
// 2x2x2 cells around x accumulates, from the same photons, the kernel sum at r_b and the
// closed-form difference K_{r'} - K_r (shared/photon_density.h). Photons arriving from behind
// the surface (dot(w_i, n) <= 0) are rejected.
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
layout(constant_id = kSpecSortedTexels) const bool kSortedTexels = true;
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Uvec4ArrayRef { uvec4 v[]; };

uvec4 sortedTexel(Uvec4ArrayRef sorted, uint t) {
    return kSortedTexels ? texelFetch(sortedTexels, int(t)) : sorted.v[t];
}

struct GatherSums {
    vec3 base;        // sum Phi_i W_{r_b}
    vec3 difference;  // sum Phi_i (W_{r'} - W_r)
    uint found;       // photons within r_b on the front side
};

// rb2 = r_b^2; logRadius2 = ln(r^2 / r_b^2), logStep2 = ln(r'^2 / r^2); no difference when
// difference is false.
GatherSums gatherPhotons(PhotonMapRef map, vec3 x, vec3 n, float rb2, bool difference, float logRadius2,
                         float logStep2, uint kernel, uint sliceBegin) {
    GatherSums s;
    s.base = vec3(0.0);
    s.difference = vec3(0.0);
    s.found = 0u;
    float cellSize = map.h.cellSize;
    uint tableSize = map.h.tableSize;
    Uvec4ArrayRef sorted = Uvec4ArrayRef(uvec2(map.h.sortedLo, map.h.sortedHi));
    UintArrayRef cellStart = UintArrayRef(uvec2(map.h.cellStartLo, map.h.cellStartHi));
    float rj2 = rb2 * exp(logRadius2);

    ivec3 low = gridNeighbourhood(x, cellSize);
    uint visited[8];
    for (uint c = 0u; c < 8u; ++c) {
        uint h = gridHash(low + ivec3(int(c & 1u), int((c >> 1u) & 1u), int(c >> 2u)), tableSize);
        // Two cells of the neighbourhood may share a bucket: visit each bucket once.
        bool seen = false;
        for (uint k = 0u; k < c; ++k) seen = seen || visited[k] == h;
        visited[c] = h;
        if (seen) continue;
        // The scatter left the end of bucket h's range in cellStart[h], so bucket h - 1's end is
        // where h begins (hash_grid_build.comp).
        uint begin = h == 0u ? 0u : cellStart.v[h - 1u];
        uint count = cellStart.v[h] - begin;
        if (sliceBegin >= count) continue;
        uint first = begin + sliceBegin;
        uint last = first + min(count - sliceBegin, kGatherSlicePhotons);
        for (uint i = first; i < last; ++i) {
            // The position first: most photons of the cells lie beyond r_b, and the rest of the
            // photon is read only for those within (measured 7% faster than reading it whole).
            vec3 d = x - uintBitsToFloat(sortedTexel(sorted, 2u * i).xyz);
            float d2 = dot(d, d);
            if (!(d2 < rb2)) continue;
            uvec4 rest = sortedTexel(sorted, 2u * i + 1u);  // power, direction
            if (dot(decodeDirection(rest.w), n) <= 0.0) continue;
            vec3 power = uintBitsToFloat(rest.xyz);
            s.found += 1u;
            s.base += power * kernelWeight(kernel, d2, rb2);
            if (difference && d2 < rj2) s.difference += power * kernelDifference(kernel, d2, rj2, logStep2);
        }
    }
    return s;
}
