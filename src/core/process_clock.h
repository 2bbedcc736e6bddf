// Seconds since this process started (Linux: /proc/self/stat start time against CLOCK_BOOTTIME),
// so that start-up costs before main() (loading shared libraries) count too. 10 ms resolution;
// returns a negative value where the start time is unavailable.
#pragma once

#include <cstdio>
#include <cstring>
#include <ctime>

#include <unistd.h>

namespace telescope {

inline double secondsSinceProcessStart() {
    std::FILE* f = std::fopen("/proc/self/stat", "r");
    if (!f) return -1.0;
    char buf[1024];
    size_t n = std::fread(buf, 1, sizeof(buf) - 1, f);
    std::fclose(f);
    buf[n] = '\0';
    // Field 22 (starttime, clock ticks after boot); fields after the ')' closing the command name.
    const char* p = std::strrchr(buf, ')');
    if (!p) return -1.0;
    unsigned long long start = 0;
    int field = 2;
    for (const char* c = p + 1; *c; ++c) {
        if (*c == ' ') {
            ++field;
            if (field == 22) {
                std::sscanf(c + 1, "%llu", &start);
                break;
            }
        }
    }
    long ticks = sysconf(_SC_CLK_TCK);
    timespec now{};
    if (field != 22 || ticks <= 0 || clock_gettime(CLOCK_BOOTTIME, &now) != 0) return -1.0;
    return double(now.tv_sec) + 1e-9 * double(now.tv_nsec) - double(start) / double(ticks);
}

}  // namespace telescope
