// The majorant grid walk (shaders/shared/majorant_walk.h) on the CPU: for random segments through
// random grids (zero direction components and segments leaving the grid included), the walk's
// pieces cover [0, min(len, exit)] without gaps, each piece's points lie in the piece's cell, and
// every cell a dense sampling of the segment touches is visited, once, in order. Control: a walk
// that steps the wrong axis at ties fails the same checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "shared/majorant_walk.h"

using namespace telescope::shader;

namespace {

struct Piece {
    glm::ivec3 cell;
    float t0, t1;
};

// The walk's pieces; `broken` steps x instead of y when y's crossing is the nearest (the control).
std::vector<Piece> walkPieces(glm::vec3 xo, glm::vec3 xd, glm::ivec3 res, float len, bool broken) {
    std::vector<Piece> pieces;
    MajorantWalk w = majorantWalkStart(xo, xd, res, len);
    float t = 0.0f;
    for (int guard = 0; guard < 10000; ++guard) {
        const float end = majorantWalkCellEnd(w);
        pieces.push_back({w.cell, t, end});
        t = end;
        if (broken && end < len && w.tNext.y < w.tNext.x && w.tNext.y <= w.tNext.z) {
            w.cell.x += w.stepDir.x;  // the wrong axis
            w.tNext.y += w.tDelta.y;
            if (glm::any(glm::lessThan(w.cell, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(w.cell, res))) break;
            continue;
        }
        if (!majorantWalkNext(w)) break;
    }
    return pieces;
}

bool inside(glm::vec3 p, glm::ivec3 c, float slack) {
    for (int a = 0; a < 3; ++a)
        if (p[a] < float(c[a]) - slack || p[a] > float(c[a] + 1) + slack) return false;
    return true;
}

// Failed checks over `segments` random segments.
int failures(uint32_t seed, int segments, bool broken) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int failed = 0;
    for (int s = 0; s < segments; ++s) {
        const glm::ivec3 res(1 + int(u(gen) * 7), 1 + int(u(gen) * 7), 1 + int(u(gen) * 7));
        const glm::vec3 xo = glm::vec3(u(gen), u(gen), u(gen)) * glm::vec3(res);
        glm::vec3 xd = glm::normalize(glm::vec3(u(gen), u(gen), u(gen)) - 0.5f);
        if (s % 5 == 0) xd[s % 3] = 0.0f;  // a zero component: the walk never crosses that axis
        if (s % 7 == 0) xd = glm::vec3(0.0f, 0.0f, 1.0f);
        xd *= 0.5f + 2.0f * u(gen);
        const float len = 0.1f + 20.0f * u(gen);
        const std::vector<Piece> pieces = walkPieces(xo, xd, res, len, broken);
        bool ok = pieces.front().t0 == 0.0f;
        for (size_t i = 0; i < pieces.size(); ++i) {
            const Piece& p = pieces[i];
            ok = ok && p.t1 >= p.t0 && (i == 0 || p.t0 == pieces[i - 1].t1);
            // Points of the piece lie in its cell (a float ulp of slack at the faces).
            for (float f : {0.01f, 0.5f, 0.99f}) ok = ok && inside(xo + (p.t0 + f * (p.t1 - p.t0)) * xd, p.cell, 1e-4f);
        }
        // The walk ends at len, or where the segment leaves the grid.
        const float end = pieces.back().t1;
        const glm::vec3 after = xo + (end * 1.0001f + 1e-4f) * xd;
        ok = ok && (end >= len || glm::any(glm::lessThan(after, glm::vec3(0.0f))) ||
                    glm::any(glm::greaterThanEqual(after, glm::vec3(res))));
        // Every cell dense samples of [0, end] touch is a piece's cell, visited once.
        std::vector<glm::ivec3> cells;
        for (const Piece& p : pieces) cells.push_back(p.cell);
        for (size_t i = 0; i < cells.size(); ++i)
            for (size_t j = i + 1; j < cells.size(); ++j) ok = ok && cells[i] != cells[j];
        for (int k = 1; k < 400; ++k) {
            const glm::vec3 x = xo + (end * float(k) / 400.0f) * xd;
            const glm::ivec3 c = glm::ivec3(glm::floor(x));
            if (glm::any(glm::lessThan(c, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(c, res))) continue;
            bool nearFace = false;
            for (int a = 0; a < 3; ++a) nearFace = nearFace || std::abs(x[a] - std::round(x[a])) < 1e-3f;
            if (!nearFace) ok = ok && std::find(cells.begin(), cells.end(), c) != cells.end();
        }
        failed += ok ? 0 : 1;
    }
    return failed;
}

}  // namespace

TEST(MajorantWalk, PiecesCoverTheSegmentCellByCell) {
    EXPECT_EQ(failures(11, 20000, false), 0);
    const int control = failures(11, 20000, true);
    std::printf("control: %d of 20000 segments fail\n", control);
    EXPECT_GT(control, 1000) << "the control (a wrong axis at some steps) passed";
}

TEST(MajorantWalk, AStartOutsideIsClampedAndAZeroDirectionStaysInItsCell) {
    // rounding can leave the origin a hair outside the grid: the walk starts in the border cell
    MajorantWalk w = majorantWalkStart(glm::vec3(-1e-6f, 0.5f, 3.0f), glm::vec3(1.0f, 0.0f, 0.0f), glm::ivec3(4, 1, 3), 10.0f);
    EXPECT_EQ(w.cell, glm::ivec3(0, 0, 2));
    EXPECT_EQ(w.tNext.y, kInfinity);
    EXPECT_EQ(w.tNext.z, kInfinity);
    int cells = 1;
    while (majorantWalkNext(w)) ++cells;
    EXPECT_EQ(cells, 4) << "x crosses the 4 cells of its row, then leaves the grid";
}
