// SPDX-License-Identifier: BSD-3-Clause
// Runs inside a qemu VM with the kernel's vivid driver (scripts/vivid-test.sh): the frontend's
// V4L2 source against a real driver. Prints GoogleTest-style lines and a summary.
//
// Needs vivid with "100% Colorbar": the eight bars are 80 px wide at 640x480; green is the
// fourth (columns 240-319), Y/U/V 144/54/34.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "cylfe/error.hpp"
#include "cylfe/rawlog.hpp"
#include "cylfe/v4l2.hpp"

extern "C" {
#include "cyl/colortable.h"
#include "cyl/segment.h"
}

using namespace cylfe;

namespace {

std::string g_dev = "/dev/video0";
int g_failed_checks = 0;

#define EXPECT(cond, ...)                                                       \
    do {                                                                        \
        if (!(cond)) {                                                          \
            std::printf("  check failed (%s:%d): %s: ", __FILE__, __LINE__, #cond); \
            std::printf(__VA_ARGS__);                                           \
            std::printf("\n");                                                  \
            g_failed_checks++;                                                  \
        }                                                                       \
    } while (0)

// Run f; return the Error's text ("" if none was thrown).
std::string error_of(const std::function<void()> &f)
{
    try {
        f();
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}

V4L2Options opts(uint32_t fourcc)
{
    V4L2Options o;
    o.device = g_dev;
    o.fourcc = fourcc;
    o.width = 640;
    o.height = 480;
    o.fps = 30;
    o.timeout_ms = 3000;
    return o;
}

// True when the frame shows vivid's 100% colour bars (white first bar, green fourth).
bool showing_colourbars(const cyl_image &img)
{
    const struct { uint32_t x; int y, u, v; } want[] = {{40, 235, 128, 128}, {280, 144, 54, 34}};
    for (const auto &w : want) {
        for (uint32_t row : {60u, 240u, 420u}) {
            uint8_t y = 0, u = 0, v = 0;
            if (cyl_image_pixel(&img, w.x, row, &y, &u, &v) != CYL_OK) return false;
            if (std::abs(y - w.y) > 12 || std::abs(u - w.u) > 12 || std::abs(v - w.v) > 12) return false;
        }
    }
    return true;
}

void colourbars(V4L2Source &s)
{
    s.set_control("Test Pattern", "100% Colorbar");
    s.set_control("OSD Text Mode", "None");
}

// Capture 30 frames in a format: increasing timestamps, one green blob at columns 240-319
// with a table trained on the green bar of the first frame, and a raw log round trip.
void capture(uint32_t fourcc)
{
    V4L2Source src(opts(fourcc));
    colourbars(src);
    EXPECT(src.info().width == 640 && src.info().height == 480, "size %ux%u", src.info().width, src.info().height);
    EXPECT(src.info().fourcc == fourcc, "format %s", fourcc_str(src.info().fourcc).c_str());
    static cyl_colortable table;
    cyl_colortable_init(&table);
    cyl_colortable_set_class(&table, 0, "green", 0, 255, 0);
    std::vector<uint32_t> work(cyl_train_workspace_size() / 4);
    std::vector<uint8_t> mem(cyl_segment_mem_size(20000, 256));
    cyl_segmentation seg;
    cyl_segmentation_init(&seg, mem.data(), mem.size(), 20000, 256);
    RawLogWriter rec("/tmp/capture.cylraw", src.info());
    SourceEvent ev;
    int64_t last_t = -1;
    int64_t last_seq = -1;
    int frames = 0, good = 0, warmup = 0;
    uint32_t first_crc = 0;
    while (frames < 30) {
        EXPECT(src.next(ev), "stream ended early");
        // Frames queued before the pattern control was set still show the old pattern; how many
        // depends on the VM's speed (a sanitizer build under emulation is slow), so wait for the
        // bars themselves: green at the middle of the fourth bar and white at the first.
        if (!showing_colourbars(ev.image)) {
            warmup++;
            EXPECT(warmup < 20, "no colour bars after %d frames", warmup);
            if (warmup >= 20) return;
            continue;
        }
        EXPECT(ev.header.t_ns > last_t, "timestamp %lld after %lld", (long long)ev.header.t_ns, (long long)last_t);
        EXPECT((int64_t)ev.header.seq > last_seq, "sequence %llu after %lld", (unsigned long long)ev.header.seq,
               (long long)last_seq);
        last_t = ev.header.t_ns;
        last_seq = (int64_t)ev.header.seq;
        if (frames == 0) {
            cyl_roi bar = {250, 40, 60, 400};  // inside the green bar
            uint8_t box[6];
            check(cyl_colortable_train(&table, 0, &ev.image, &bar, nullptr, work.data(), work.size() * 4, box), "train");
            std::printf("  trained green: U %d-%d V %d-%d Y %d-%d\n", box[0], box[1], box[2], box[3], box[4], box[5]);
            first_crc = cyl_crc32(0, ev.data, ev.header.size);
        }
        rec.frame(ev.header.seq, ev.header.t_ns, ev.data, ev.header.size, ev.header.flags);
        check(cyl_segment(&table, &ev.image, nullptr, &seg), "segment");
        if (seg.n_blobs == 1 && seg.blobs[0].x0 == 240 && seg.blobs[0].x1 == 319 && seg.blobs[0].y0 == 0 &&
            seg.blobs[0].y1 == 479)
            good++;
        else if (seg.n_blobs >= 1)
            std::printf("  frame %d: %u blobs, first x %u-%u y %u-%u\n", frames, seg.n_blobs, seg.blobs[0].x0,
                        seg.blobs[0].x1, seg.blobs[0].y0, seg.blobs[0].y1);
        else
            std::printf("  frame %d: no blob\n", frames);
        frames++;
    }
    rec.close();
    EXPECT(good == 30, "%d of 30 frames gave exactly one green blob at columns 240-319", good);
    std::printf("  %s: 30 frames after %d warm-up frames, %d with one green blob at 240-319, interval %.3f s, "
                "dropped %llu\n",
                fourcc_str(fourcc).c_str(), warmup, good, src.frame_interval_s(), (unsigned long long)src.dropped());
    RawLogReader rd("/tmp/capture.cylraw");
    RecordHeader h;
    std::vector<uint8_t> payload;
    int n = 0;
    while (rd.next(h, payload)) {
        if (n == 0) EXPECT(cyl_crc32(0, payload.data(), payload.size()) == first_crc, "first frame differs after replay");
        n++;
    }
    EXPECT(n == 30 && !rd.truncated(), "raw log replayed %d frames", n);
}

void test_capture_yuyv() { capture(fourcc('Y', 'U', 'Y', 'V')); }
void test_capture_nv12() { capture(fourcc('N', 'V', '1', '2')); }

void test_no_such_device()
{
    V4L2Options o = opts(0);
    o.device = "/dev/video42";
    std::string e = error_of([&] { V4L2Source s(o); });
    EXPECT(e.find("no such device") != std::string::npos, "got '%s'", e.c_str());
    o.device = "/dev/null";
    e = error_of([&] { V4L2Source s(o); });
    EXPECT(e.find("not a V4L2 device") != std::string::npos, "got '%s'", e.c_str());
}

void test_not_a_capture_device()
{
    std::string other;
    for (const auto &d : v4l2_list_devices())
        if (!d.capture && other.empty()) other = d.path;
    EXPECT(!other.empty(), "vivid created no non-capture video node");
    if (other.empty()) return;
    V4L2Options o = opts(0);
    o.device = other;
    std::string e = error_of([&] { V4L2Source s(o); });
    EXPECT(e.find("not a video capture device") != std::string::npos, "%s: got '%s'", other.c_str(), e.c_str());
    std::printf("  %s: %s\n", other.c_str(), e.c_str());
}

void test_busy()
{
    V4L2Source a(opts(fourcc('Y', 'U', 'Y', 'V')));
    SourceEvent ev;
    a.next(ev);
    std::string e = error_of([&] { V4L2Source b(opts(fourcc('Y', 'U', 'Y', 'V'))); });
    EXPECT(e.find("busy") != std::string::npos, "got '%s'", e.c_str());
    std::printf("  second open: %s\n", e.c_str());
}

void test_format_not_offered()
{
    std::string e = error_of([&] { V4L2Source s(opts(fourcc('4', '4', '4', 'P'))); });
    EXPECT(e.find("not offered") != std::string::npos, "got '%s'", e.c_str());
    std::printf("  %s\n", e.substr(0, 100).c_str());
    V4L2Options o = opts(fourcc('Y', 'U', 'Y', 'V'));
    o.width = 641;  // vivid rounds odd widths
    e = error_of([&] { V4L2Source s(o); });
    EXPECT(e.find("not offered") != std::string::npos, "odd width: got '%s'", e.c_str());
}

void test_timeout()
{
    V4L2Options o = opts(fourcc('Y', 'U', 'Y', 'V'));
    o.fps = 0.2;          // one frame every 5 s
    o.timeout_ms = 400;
    std::string e = error_of([&] {
        V4L2Source s(o);
        SourceEvent ev;
        for (int i = 0; i < 3; i++) s.next(ev);
    });
    EXPECT(e.find("timeout") != std::string::npos, "got '%s'", e.c_str());
}

void test_dropped_frames_and_error_flag()
{
    V4L2Source s(opts(fourcc('Y', 'U', 'Y', 'V')));
    SourceEvent ev;
    s.set_control("Percentage of Dropped Buffers", "50");
    for (int i = 0; i < 20; i++) s.next(ev);
    uint64_t dropped = s.dropped();
    s.set_control("Percentage of Dropped Buffers", "0");
    EXPECT(dropped > 0, "no dropped frame counted with 50%% dropped buffers");
    std::printf("  50%% dropped buffers: %llu of %llu+%llu frames counted as dropped\n", (unsigned long long)dropped,
                (unsigned long long)s.frames(), (unsigned long long)dropped);
    s.set_control("Inject V4L2_BUF_FLAG_ERROR", "0");
    bool flagged = false;
    for (int i = 0; i < 5 && !flagged; i++) {
        s.next(ev);
        flagged = ev.header.flags & 1u;
    }
    EXPECT(flagged, "no frame came back flagged after injecting V4L2_BUF_FLAG_ERROR");
}

void test_device_gone_mid_stream()
{
    V4L2Source s(opts(fourcc('Y', 'U', 'Y', 'V')));
    SourceEvent ev;
    s.next(ev);
    s.set_control("Disconnect", "0");
    std::string e = error_of([&] {
        for (int i = 0; i < 5; i++) s.next(ev);
    });
    EXPECT(e.find("disconnected") != std::string::npos || e.find("device error") != std::string::npos,
           "got '%s'", e.c_str());
    std::printf("  after Disconnect: %s\n", e.c_str());
}

} // namespace

int main(int argc, char **argv)
{
    if (argc > 1) g_dev = argv[1];
    struct T { const char *name; void (*fn)(); };
    const T tests[] = {
        {"capture_yuyv_640x480", test_capture_yuyv},
        {"capture_nv12_640x480", test_capture_nv12},
        {"no_such_device", test_no_such_device},
        {"not_a_capture_device", test_not_a_capture_device},
        {"busy", test_busy},
        {"format_not_offered", test_format_not_offered},
        {"timeout", test_timeout},
        {"dropped_frames_and_error_flag", test_dropped_frames_and_error_flag},
        {"device_gone_mid_stream", test_device_gone_mid_stream},  // last: vivid stays gone while open
    };
    int passed = 0, failed = 0;
    for (const T &t : tests) {
        std::printf("[ RUN      ] vivid.%s\n", t.name);
        std::fflush(stdout);
        int before = g_failed_checks;
        try {
            t.fn();
        } catch (const std::exception &e) {
            std::printf("  unexpected error: %s\n", e.what());
            g_failed_checks++;
        }
        if (g_failed_checks == before) { passed++; std::printf("[       OK ] vivid.%s\n", t.name); }
        else { failed++; std::printf("[  FAILED  ] vivid.%s\n", t.name); }
        std::fflush(stdout);
    }
    std::printf("[==========] %d tests ran.\n", passed + failed);
    std::printf("[  PASSED  ] %d tests.\n", passed);
    if (failed) std::printf("[  FAILED  ] %d tests.\n", failed);
    return failed ? 1 : 0;
}
