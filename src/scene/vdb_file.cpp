// Loads libtelescope_vdb.so on first use (src/scene/vdb_file.h says why) and copies its result.
#include "scene/vdb_file.h"

#include <mutex>
#include <stdexcept>

#include <fmt/format.h>

#include "scene/plugin_loader.h"

#ifndef TELESCOPE_VDB_PLUGIN_PATH
#define TELESCOPE_VDB_PLUGIN_PATH ""
#endif

namespace telescope {

namespace {

struct VdbPlugin {
    TelescopeVdbReadFn read = nullptr;
    TelescopeVdbFreeFn release = nullptr;
    std::string error;
};

const VdbPlugin& plugin() {
    static VdbPlugin p;
    static std::once_flag once;
    std::call_once(once, [] {
        const PluginHandle h = openPlugin(
            {"libtelescope_vdb.so", TELESCOPE_VDB_PLUGIN_PATH, "the OpenVDB module", "read VDB files", "OpenVDB"});
        if (!h.handle) {
            p.error = h.error;
            return;
        }
        p.read = pluginSymbol<TelescopeVdbReadFn>(h, "telescopeVdbRead");
        p.release = pluginSymbol<TelescopeVdbFreeFn>(h, "telescopeVdbFree");
        if (!p.read || !p.release) p.error = fmt::format("the OpenVDB module {} lacks its entry points", h.path);
    });
    return p;
}

}  // namespace

VdbFileData readVdbFile(const TelescopeVdbRequest& request, int32_t& status) {
    const VdbPlugin& p = plugin();
    if (!p.read) {
        status = kVdbCannotOpen;
        throw std::runtime_error(p.error);
    }
    TelescopeVdbResult r{};
    status = p.read(&request, &r);
    if (status != kVdbOk) {
        std::string message(r.message);
        p.release(&r);
        throw std::runtime_error(message);
    }
    VdbFileData d;
    d.activeMin = glm::ivec3(r.activeMin[0], r.activeMin[1], r.activeMin[2]);
    d.activeMax = glm::ivec3(r.activeMax[0], r.activeMax[1], r.activeMax[2]);
    d.lo = glm::ivec3(r.lo[0], r.lo[1], r.lo[2]);
    d.res = glm::uvec3(r.res[0], r.res[1], r.res[2]);
    d.indexOrigin = glm::dvec3(r.indexOrigin[0], r.indexOrigin[1], r.indexOrigin[2]);
    d.voxelSize = glm::dvec3(r.voxelSize[0], r.voxelSize[1], r.voxelSize[2]);
    const size_t n = size_t(d.res.x) * d.res.y * d.res.z;
    d.density.assign(r.density, r.density + n);
    if (r.emission) d.emission.assign(r.emission, r.emission + 3 * n);
    p.release(&r);
    return d;
}

}  // namespace telescope
