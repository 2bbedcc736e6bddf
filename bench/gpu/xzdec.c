/* A minimal .xz decompressor, stdin to stdout, for machines without xz-utils: bench/gpu/make-bundle
 * links it statically (liblzma.a and glibc's libc.a) next to the bundle, and bench/gpu/run-on-gpu
 * uses it when `xz` is missing. Build: cc -O2 -static -o xzdec xzdec.c -l:liblzma.a */
#include <lzma.h>
#include <stdio.h>
#include <stdlib.h>

int main(void) {
    static uint8_t in[1 << 16], out[1 << 20];
    lzma_stream s = LZMA_STREAM_INIT;
    if (lzma_stream_decoder(&s, UINT64_MAX, LZMA_CONCATENATED) != LZMA_OK) {
        fprintf(stderr, "xzdec: cannot start the decoder\n");
        return 1;
    }
    lzma_action action = LZMA_RUN;
    s.next_out = out;
    s.avail_out = sizeof out;
    for (;;) {
        if (s.avail_in == 0 && action == LZMA_RUN) {
            s.next_in = in;
            s.avail_in = fread(in, 1, sizeof in, stdin);
            if (ferror(stdin)) { perror("xzdec: read"); return 1; }
            if (feof(stdin)) action = LZMA_FINISH;
        }
        lzma_ret r = lzma_code(&s, action);
        if (s.avail_out == 0 || r == LZMA_STREAM_END) {
            size_t n = sizeof out - s.avail_out;
            if (fwrite(out, 1, n, stdout) != n) { perror("xzdec: write"); return 1; }
            s.next_out = out;
            s.avail_out = sizeof out;
        }
        if (r == LZMA_STREAM_END) break;
        if (r != LZMA_OK) {
            fprintf(stderr, "xzdec: corrupt or truncated input (lzma error %d)\n", (int)r);
            return 1;
        }
    }
    lzma_end(&s);
    return fflush(stdout) == 0 ? 0 : 1;
}
