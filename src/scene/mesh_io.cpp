// Triangle meshes on disk: Tungsten's .wo3 and Wavefront .obj (through tinyobjloader).
#include "scene/mesh_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

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
    for (uint64_t i = 0; i < numVerts; ++i) {
        std::memcpy(&mesh.positions[i], bytes.data() + offset + i * kVertexBytes, 12);
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
    for (uint64_t i = 0; i < numTris; ++i) {
        const char* record = bytes.data() + offset + i * kTriangleBytes;
        std::memcpy(mesh.triangles[i].data(), record, 12);
        std::memcpy(&mesh.materials[i], record + 12, 4);
        for (uint32_t index : mesh.triangles[i])
            if (index >= numVerts) malformed(fmt::format("triangle {} uses vertex {} of {}", i, index, numVerts));
        for (int k = 0; k < 3; ++k) mesh.uvs[i][k] = vertexUvs[mesh.triangles[i][k]];
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
            }
            mesh.triangles.push_back(tri);
            mesh.uvs.push_back(uv);
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

}  // namespace telescope
