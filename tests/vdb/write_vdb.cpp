// telescope_write_vdb: writes small OpenVDB files for the tests (tests/vdb_render_test.cpp), with
// OpenVDB itself, independently of the reader in src/vdb_plugin.
//
//   telescope_write_vdb OUT.vdb [--voxel-size H] GRID...
//   GRID: --float NAME X0 Y0 Z0 X1 Y1 Z1 FROM TO   float grid, active voxels [X0..X1] x [Y0..Y1] x [Z0..Z1],
//                                                   FROM at z = Z0 to TO at z = Z1, linear in between
//         --vec3 NAME X0 Y0 Z0 X1 Y1 Z1 R G B       vec3 float grid, constant
//         --int NAME X0 Y0 Z0 X1 Y1 Z1 V            int32 grid (a grid of the wrong type)
// Index (0, 0, 0) sits at the world origin; every grid has voxel size H (1 by default).
#include <openvdb/openvdb.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

[[noreturn]] void usage(const char* why) {
    std::fprintf(stderr, "telescope_write_vdb: %s\n", why);
    std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) usage("usage: telescope_write_vdb OUT.vdb [--voxel-size H] GRID...");
    openvdb::initialize();
    const std::string out = argv[1];
    double voxel = 1.0;
    openvdb::GridPtrVec grids;
    int i = 2;
    auto need = [&](int n) {
        if (i + n > argc) usage("missing arguments");
    };
    auto box = [&](int at) {
        return openvdb::CoordBBox(openvdb::Coord(std::atoi(argv[at]), std::atoi(argv[at + 1]), std::atoi(argv[at + 2])),
                                  openvdb::Coord(std::atoi(argv[at + 3]), std::atoi(argv[at + 4]), std::atoi(argv[at + 5])));
    };
    while (i < argc) {
        const std::string opt = argv[i];
        if (opt == "--voxel-size") {
            need(2);
            voxel = std::atof(argv[i + 1]);
            i += 2;
        } else if (opt == "--float") {
            need(10);
            const openvdb::CoordBBox b = box(i + 2);
            const float from = float(std::atof(argv[i + 8])), to = float(std::atof(argv[i + 9]));
            openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(0.0f);
            g->setName(argv[i + 1]);
            g->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
            auto acc = g->getAccessor();
            const int nz = b.max().z() - b.min().z();
            for (auto it = b.begin(); it; ++it) {
                const openvdb::Coord c = *it;
                const float s = nz > 0 ? float(c.z() - b.min().z()) / float(nz) : 0.0f;
                acc.setValue(c, from + (to - from) * s);
            }
            grids.push_back(g);
            i += 10;
        } else if (opt == "--vec3") {
            need(11);
            const openvdb::CoordBBox b = box(i + 2);
            const openvdb::Vec3f v(float(std::atof(argv[i + 8])), float(std::atof(argv[i + 9])), float(std::atof(argv[i + 10])));
            openvdb::Vec3fGrid::Ptr g = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
            g->setName(argv[i + 1]);
            g->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
            g->fill(b, v, true);
            grids.push_back(g);
            i += 11;
        } else if (opt == "--int") {
            need(9);
            const openvdb::CoordBBox b = box(i + 2);
            openvdb::Int32Grid::Ptr g = openvdb::Int32Grid::create(0);
            g->setName(argv[i + 1]);
            g->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
            g->fill(b, std::atoi(argv[i + 8]), true);
            grids.push_back(g);
            i += 9;
        } else {
            usage(("unknown option " + opt).c_str());
        }
    }
    openvdb::io::File(out).write(grids);
    return 0;
}
