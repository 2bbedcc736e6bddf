// Triangle meshes on disk (Tungsten's .wo3 and Wavefront .obj), in the mesh's local space.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace telescope {

struct MeshData {
    std::vector<glm::vec3> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<int32_t> materials;  // per triangle, index into the primitive's bsdf list
    std::vector<std::array<glm::vec2, 3>> uvs;  // per triangle, its vertices' uvs (0 where the file has none)
    // Per triangle, the file's normals at its vertices (.wo3 always has them, .obj its "vn"; zero
    // where the file has none), and each corner's vertex index for welding (= triangles).
    std::vector<std::array<glm::vec3, 3>> normals;
};

// Tungsten's recomputed smooth vertex normals (its `recompute_normals` with `smooth`), in the
// mesh's own space: corners that share a position share a normal, the sum of the area-weighted
// normals of the faces there whose unit normal is within 0.15 pi of the corner's own group; a
// face deviating more than that from the first face at its vertex keeps its own flat normal at
// that corner. Returns per triangle its three unit corner normals.
std::vector<std::array<glm::vec3, 3>> smoothVertexNormals(const MeshData& mesh);

// Reads a .wo3 or .obj file (by its extension, any case). Throws InputError naming sceneFile and
// key (the "file" key that named the mesh) for a missing, unsupported or malformed file.
MeshData loadMesh(const std::string& path, const std::string& sceneFile, const std::string& key);

}  // namespace telescope
