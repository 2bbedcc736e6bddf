// Triangle meshes on disk: Tungsten's .wo3 and Wavefront .obj (through tinyobjloader).
#include "scene/mesh_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unordered_map>

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include "core/error.h"

namespace telescope {

namespace {

namespace fs = std::filesystem;

struct MeshReader {
    std::string file;  // the scene file, for messages
    fs::path path;
    std::string key;   // the "file" key that named the mesh

    [[noreturn]] void fail(const std::string& k, const std::string& what) const { throw InputError(file, k, what); }
    MeshData wo3() const;
    MeshData obj() const;
};

// .wo3: uint64 vertex count, {pos, normal, uv} float records, uint64 triangle count,
// {uint32 v0, v1, v2; int32 material} records; little-endian, no header.
MeshData MeshReader::wo3() const {
    static_assert(std::endian::native == std::endian::little, ".wo3 is read with memcpy");
    constexpr uint64_t kVertexBytes = 32, kTriangleBytes = 16;
    auto malformed = [&](const std::string& why) -> void { fail(key, fmt::format("malformed .wo3 '{}': {}", path.string(), why)); };

    std::ifstream in(path, std::ios::binary);
    if (!in) fail(key, fmt::format("cannot open mesh file '{}'", path.string()));
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

    uint64_t offset = 0;
    auto readU64 = [&]() {
        uint64_t n = 0;
        if (bytes.size() - offset < 8) malformed("the file is truncated");
        std::memcpy(&n, bytes.data() + offset, 8);
        offset += 8;
        return n;
    };
    MeshData mesh;
    const uint64_t numVerts = readU64();
    if (numVerts > (bytes.size() - offset) / kVertexBytes) malformed(fmt::format("{} vertices do not fit in the file", numVerts));
    mesh.positions.resize(numVerts);
    std::vector<glm::vec2> vertexUvs(numVerts);
    std::vector<glm::vec3> vertexNormals(numVerts);
    for (uint64_t i = 0; i < numVerts; ++i) {
        std::memcpy(&mesh.positions[i], bytes.data() + offset + i * kVertexBytes, 12);
        std::memcpy(&vertexNormals[i], bytes.data() + offset + i * kVertexBytes + 12, 12);
        std::memcpy(&vertexUvs[i], bytes.data() + offset + i * kVertexBytes + 24, 8);
    }
    offset += numVerts * kVertexBytes;

    const uint64_t numTris = readU64();
    if (numTris > (bytes.size() - offset) / kTriangleBytes) malformed(fmt::format("{} triangles do not fit in the file", numTris));
    if (offset + numTris * kTriangleBytes != bytes.size())
        malformed(fmt::format("{} bytes after the triangle list", bytes.size() - offset - numTris * kTriangleBytes));
    mesh.triangles.resize(numTris);
    mesh.materials.resize(numTris);
    mesh.uvs.resize(numTris);
    mesh.normals.resize(numTris);
    for (uint64_t i = 0; i < numTris; ++i) {
        const char* record = bytes.data() + offset + i * kTriangleBytes;
        std::memcpy(mesh.triangles[i].data(), record, 12);
        std::memcpy(&mesh.materials[i], record + 12, 4);
        for (uint32_t index : mesh.triangles[i])
            if (index >= numVerts) malformed(fmt::format("triangle {} uses vertex {} of {}", i, index, numVerts));
        for (int k = 0; k < 3; ++k) {
            mesh.uvs[i][k] = vertexUvs[mesh.triangles[i][k]];
            const glm::vec3 n = vertexNormals[mesh.triangles[i][k]];
            mesh.normals[i][k] = std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) ? n : glm::vec3(0.0f);
        }
    }
    for (uint64_t i = 0; i < numVerts; ++i)
        if (!std::isfinite(mesh.positions[i].x) || !std::isfinite(mesh.positions[i].y) || !std::isfinite(mesh.positions[i].z))
            malformed(fmt::format("vertex {} is not finite", i));
    return mesh;
}

// .obj through tinyobjloader, triangulated; per-triangle material = usemtl index (0 if none).
MeshData MeshReader::obj() const {
    auto malformed = [&](std::string why) -> void {
        while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
        std::replace(why.begin(), why.end(), '\n', ' ');
        fail(key, fmt::format("malformed .obj '{}': {}", path.string(), why));
    };
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    config.mtl_search_path = path.parent_path().string();
    tinyobj::ObjReader reader;
    if (!reader.ParseFromFile(path.string(), config)) malformed(reader.Error().empty() ? "parse failed" : reader.Error());

    MeshData mesh;
    const std::vector<tinyobj::real_t>& v = reader.GetAttrib().vertices;
    const std::vector<tinyobj::real_t>& texcoords = reader.GetAttrib().texcoords;
    const std::vector<tinyobj::real_t>& vn = reader.GetAttrib().normals;
    if (v.size() % 3 != 0) malformed("incomplete vertex list");
    mesh.positions.resize(v.size() / 3);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        mesh.positions[i] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
        if (!std::isfinite(v[3 * i]) || !std::isfinite(v[3 * i + 1]) || !std::isfinite(v[3 * i + 2]))
            malformed(fmt::format("vertex {} is not finite", i + 1));
    }
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const tinyobj::mesh_t& m = shape.mesh;
        size_t first = 0;
        for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
            const size_t count = m.num_face_vertices[f];
            if (count != 3) malformed(fmt::format("face with {} vertices after triangulation", count));
            std::array<uint32_t, 3> tri;
            std::array<glm::vec2, 3> uv{};
            std::array<glm::vec3, 3> normal{};
            for (size_t k = 0; k < 3; ++k) {
                const int index = m.indices[first + k].vertex_index;
                if (index < 0 || size_t(index) >= mesh.positions.size())
                    malformed(fmt::format("a face in '{}' uses vertex {} of {}", shape.name, index + 1, mesh.positions.size()));
                tri[k] = uint32_t(index);
                // "vt" coordinates as the file gives them; a vertex without one gets uv 0
                const int t = m.indices[first + k].texcoord_index;
                if (t >= 0) {
                    if (2 * size_t(t) + 1 >= texcoords.size())
                        malformed(fmt::format("a face in '{}' uses texture coordinate {} of {}", shape.name, t + 1,
                                              texcoords.size() / 2));
                    uv[k] = {texcoords[2 * size_t(t)], texcoords[2 * size_t(t) + 1]};
                }
                // "vn" normals likewise (zero without)
                const int n = m.indices[first + k].normal_index;
                if (n >= 0) {
                    if (3 * size_t(n) + 2 >= vn.size())
                        malformed(fmt::format("a face in '{}' uses normal {} of {}", shape.name, n + 1, vn.size() / 3));
                    normal[k] = {vn[3 * size_t(n)], vn[3 * size_t(n) + 1], vn[3 * size_t(n) + 2]};
                }
            }
            mesh.triangles.push_back(tri);
            mesh.uvs.push_back(uv);
            mesh.normals.push_back(normal);
            mesh.materials.push_back(f < m.material_ids.size() ? std::max(m.material_ids[f], 0) : 0);
            first += count;
        }
    }
    return mesh;
}

}  // namespace

MeshData loadMesh(const std::string& pathText, const std::string& sceneFile, const std::string& key) {
    const fs::path path(pathText);
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".wo3" && ext != ".obj")
        throw InputError(sceneFile, key, fmt::format("unsupported mesh format '{}' (expected .wo3 or .obj)", path.string()));
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        throw InputError(sceneFile, key, fmt::format("cannot open mesh file '{}'", path.string()));
    const MeshReader reader{sceneFile, path, key};
    return ext == ".wo3" ? reader.wo3() : reader.obj();
}

std::vector<std::array<glm::vec3, 3>> smoothVertexNormals(const MeshData& mesh) {
    const float splitLimit = std::cos(3.14159265358979f * 0.15f);
    const size_t originalVertices = mesh.positions.size();
    // Corners: each triangle corner points at a vertex; a corner whose face deviates too far from
    // the first face seen at its vertex gets a vertex of its own (flat there).
    std::vector<glm::vec3> groupNormal(originalVertices, glm::vec3(0.0f));  // first unit face normal per vertex
    std::vector<std::array<uint32_t, 3>> corner = mesh.triangles;
    std::vector<glm::vec3> ownNormal;  // the split-off corners' flat normals, vertex originalVertices + i
    auto faceNormal = [&](size_t t) {
        const auto& tri = mesh.triangles[t];
        return glm::cross(mesh.positions[tri[1]] - mesh.positions[tri[0]], mesh.positions[tri[2]] - mesh.positions[tri[0]]);
    };
    auto unit = [](glm::vec3 n) {
        const float l = glm::length(n);
        return l > 0.0f ? n / l : glm::vec3(0.0f, 1.0f, 0.0f);
    };
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::vec3 n = unit(faceNormal(t));
        for (int k = 0; k < 3; ++k) {
            glm::vec3& g = groupNormal[corner[t][k]];
            if (g == glm::vec3(0.0f)) {
                g = n;
            } else if (glm::dot(g, n) < splitLimit) {
                corner[t][k] = uint32_t(originalVertices + ownNormal.size());
                ownNormal.push_back(n);
            }
        }
    }
    // Welding: the original vertices at each position (exact bits).
    struct PositionHash {
        size_t operator()(const glm::vec3& p) const {
            uint32_t b[3];
            std::memcpy(b, &p, 12);
            return (size_t(b[0]) * 73856093u) ^ (size_t(b[1]) * 19349663u) ^ (size_t(b[2]) * 83492791u);
        }
    };
    std::unordered_multimap<glm::vec3, uint32_t, PositionHash> atPosition;
    for (uint32_t i = 0; i < originalVertices; ++i) atPosition.insert({mesh.positions[i], i});
    std::vector<glm::vec3> sum(originalVertices, glm::vec3(0.0f));
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::vec3 area = faceNormal(t), n = unit(area);
        for (int k = 0; k < 3; ++k) {
            auto range = atPosition.equal_range(mesh.positions[mesh.triangles[t][k]]);
            for (auto it = range.first; it != range.second; ++it)
                if (glm::dot(groupNormal[it->second], n) >= splitLimit) sum[it->second] += area;
        }
    }
    std::vector<std::array<glm::vec3, 3>> out(mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = corner[t][k];
            if (v >= originalVertices) out[t][k] = ownNormal[v - originalVertices];
            else out[t][k] = sum[v] == glm::vec3(0.0f) ? groupNormal[v] : glm::normalize(sum[v]);
        }
    return out;
}

}  // namespace telescope
