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
};

// Reads a .wo3 or .obj file (by its extension, any case). Throws InputError naming sceneFile and
// key (the "file" key that named the mesh) for a missing, unsupported or malformed file.
MeshData loadMesh(const std::string& path, const std::string& sceneFile, const std::string& key);

}  // namespace telescope
