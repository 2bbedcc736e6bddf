// OpenVDB files (docs/MEDIA.md, "vdb" grids). libopenvdb and the ~10 libraries it pulls in cost
// every process about 0.05 s of CPU at start-up when linked in (docs/BENCHMARKS.md), so the
// renderer does not link it: `libtelescope_vdb.so` (src/vdb_plugin/) does, and readVdbFile() loads
// it with dlopen the first time a scene asks for a .vdb file.
//
// The plugin's C interface is below; both sides are built from this header.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

extern "C" {

// Status of a read; the message says more.
enum TelescopeVdbStatus : int32_t {
    kVdbOk = 0,
    kVdbCannotOpen = 1,        // the file is missing or not a VDB file
    kVdbNoDensityGrid = 2,     // no grid of the density name
    kVdbDensityNotFloat = 3,   // the density grid is not a FloatGrid
    kVdbNoEmissionGrid = 4,    // no grid of the emission name (only when the name is required)
    kVdbEmissionNotVec3 = 5,   // the emission grid is not a Vec3fGrid
    kVdbTooLarge = 6,          // the dense box would not fit the device's storage-buffer binding
    kVdbEmpty = 7,             // the density grid has no active voxel
};

struct TelescopeVdbRequest {
    const char* path;
    const char* densityName;
    const char* emissionName;   // nullptr: no emission
    int32_t emissionRequired;   // 1: a missing emission grid is an error, 0: no emission
    int32_t padding;            // layers of zero voxels around the active box (1 for trilinear lookups)
    uint64_t maxVoxels;         // largest dense box accepted
};

// The density grid's active voxels as a dense box of index coordinates [lo, lo + res) (x fastest),
// `padding` layers wider than the active box on each side. emission (3 floats per voxel, may be
// null) is the emission grid sampled trilinearly at the same index points, offset as Tungsten
// does between grids of different origins.
struct TelescopeVdbResult {
    int32_t status;
    int32_t activeMin[3], activeMax[3];  // active voxel bounding box (inclusive)
    int32_t lo[3];
    uint32_t res[3];
    double indexOrigin[3];   // index (0, 0, 0) in the file's world space
    double voxelSize[3];     // world size of one voxel step along each axis
    float* density;          // res[0] res[1] res[2] floats
    float* emission;         // 3 res[0] res[1] res[2] floats or nullptr
    char message[512];
};

typedef int32_t (*TelescopeVdbReadFn)(const TelescopeVdbRequest* request, TelescopeVdbResult* result);
typedef void (*TelescopeVdbFreeFn)(TelescopeVdbResult* result);

}  // extern "C"

namespace telescope {

struct VdbFileData {
    glm::ivec3 activeMin{0}, activeMax{0};
    glm::ivec3 lo{0};
    glm::uvec3 res{0};
    glm::dvec3 indexOrigin{0.0}, voxelSize{1.0};
    std::vector<float> density;
    std::vector<float> emission;  // empty: none
};

// Reads through the plugin; throws std::runtime_error with the plugin's message (the caller adds
// the scene file and key). `status` receives the TelescopeVdbStatus.
VdbFileData readVdbFile(const TelescopeVdbRequest& request, int32_t& status);

}  // namespace telescope
