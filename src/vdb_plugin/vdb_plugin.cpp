// libtelescope_vdb.so: reads OpenVDB files for src/scene/vdb_file.cpp (which loads this module with
// dlopen, so that only scenes with .vdb grids pay for libopenvdb). C interface: src/scene/vdb_file.h.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>

#include "scene/vdb_file.h"

namespace {

int32_t failWith(TelescopeVdbResult* r, int32_t status, const char* format, const char* a, const char* b = "") {
    r->status = status;
    std::snprintf(r->message, sizeof(r->message), format, a, b);
    return status;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) int32_t telescopeVdbRead(const TelescopeVdbRequest* q,
                                                                         TelescopeVdbResult* r) {
    std::memset(r, 0, sizeof(*r));
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
    try {
        openvdb::io::File file(q->path);
        try {
            file.open();
        } catch (const std::exception& e) {
            return failWith(r, kVdbCannotOpen, "cannot open VDB file '%s': %s", q->path, e.what());
        }
        if (!file.hasGrid(q->densityName))
            return failWith(r, kVdbNoDensityGrid, "VDB file '%s' has no grid named '%s'", q->path, q->densityName);
        openvdb::GridBase::Ptr base = file.readGrid(q->densityName);
        openvdb::FloatGrid::Ptr density = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
        if (!density)
            return failWith(r, kVdbDensityNotFloat, "grid '%s' of VDB file '%s' is not a float grid",
                            q->densityName, q->path);
        openvdb::Vec3fGrid::Ptr emission;
        openvdb::GridBase::Ptr emissionBase;
        if (q->emissionName) {
            if (file.hasGrid(q->emissionName)) {
                emissionBase = file.readGrid(q->emissionName);
                emission = openvdb::gridPtrCast<openvdb::Vec3fGrid>(emissionBase);
                if (!emission)
                    return failWith(r, kVdbEmissionNotVec3, "grid '%s' of VDB file '%s' is not a vec3 float grid",
                                    q->emissionName, q->path);
            } else if (q->emissionRequired) {
                return failWith(r, kVdbNoEmissionGrid, "VDB file '%s' has no grid named '%s'", q->path, q->emissionName);
            }
        }
        file.close();

        const openvdb::CoordBBox box = density->evalActiveVoxelBoundingBox();
        if (box.empty()) return failWith(r, kVdbEmpty, "grid '%s' of VDB file '%s' has no active voxel", q->densityName, q->path);
        const int pad = q->padding;
        uint64_t voxels = 1;
        for (int a = 0; a < 3; ++a) {
            r->activeMin[a] = box.min()[a];
            r->activeMax[a] = box.max()[a];
            r->lo[a] = box.min()[a] - pad;
            r->res[a] = uint32_t(box.max()[a] - box.min()[a] + 1 + 2 * pad);
            voxels *= r->res[a];
        }
        const uint64_t perVoxel = emission ? 4 : 1;
        if (voxels * perVoxel > q->maxVoxels) {
            char size[160];
            std::snprintf(size, sizeof(size), "%u x %u x %u voxels%s, more than the %llu floats a dense upload may take",
                          r->res[0], r->res[1], r->res[2], emission ? " with emission" : "",
                          (unsigned long long)q->maxVoxels);
            return failWith(r, kVdbTooLarge, "the grids of VDB file '%s' are too large: %s", q->path, size);
        }

        const openvdb::math::Transform& xf = base->transform();
        const openvdb::Vec3d origin = xf.indexToWorld(openvdb::Vec3d(0.0, 0.0, 0.0));
        const openvdb::Vec3d step = xf.indexToWorld(openvdb::Vec3d(1.0, 1.0, 1.0)) - origin;
        openvdb::Vec3d emissionOffset(0.0);
        if (emission) {
            const openvdb::Vec3d eo = emissionBase->transform().indexToWorld(openvdb::Vec3d(0.0, 0.0, 0.0));
            const openvdb::Vec3d es = emissionBase->transform().indexToWorld(openvdb::Vec3d(1.0, 1.0, 1.0)) - eo;
            for (int a = 0; a < 3; ++a) emissionOffset[a] = (origin[a] - eo[a]) / es[a];
        }
        for (int a = 0; a < 3; ++a) {
            r->indexOrigin[a] = origin[a];
            r->voxelSize[a] = step[a];
        }

        r->density = static_cast<float*>(std::malloc(voxels * sizeof(float)));
        r->emission = emission ? static_cast<float*>(std::malloc(3 * voxels * sizeof(float))) : nullptr;
        if (!r->density || (emission && !r->emission))
            return failWith(r, kVdbTooLarge, "out of memory reading VDB file '%s'%s", q->path);
        auto acc = density->getConstAccessor();
        size_t i = 0;
        for (uint32_t z = 0; z < r->res[2]; ++z)
            for (uint32_t y = 0; y < r->res[1]; ++y)
                for (uint32_t x = 0; x < r->res[0]; ++x, ++i) {
                    const openvdb::Coord c(r->lo[0] + int(x), r->lo[1] + int(y), r->lo[2] + int(z));
                    r->density[i] = acc.getValue(c);
                    if (emission) {
                        const openvdb::Vec3R p(c.x() + emissionOffset[0], c.y() + emissionOffset[1],
                                               c.z() + emissionOffset[2]);
                        const openvdb::Vec3s e = openvdb::tools::BoxSampler::sample(emission->tree(), p);
                        r->emission[3 * i + 0] = e[0];
                        r->emission[3 * i + 1] = e[1];
                        r->emission[3 * i + 2] = e[2];
                    }
                }
        r->status = kVdbOk;
        return kVdbOk;
    } catch (const std::exception& e) {
        return failWith(r, kVdbCannotOpen, "cannot read VDB file '%s': %s", q->path, e.what());
    }
}

extern "C" __attribute__((visibility("default"))) void telescopeVdbFree(TelescopeVdbResult* r) {
    std::free(r->density);
    std::free(r->emission);
    r->density = nullptr;
    r->emission = nullptr;
}
