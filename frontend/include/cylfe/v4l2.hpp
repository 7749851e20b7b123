// SPDX-License-Identifier: BSD-3-Clause
// Live capture from a V4L2 device: mmap streaming, poll with timeout, driver timestamps and
// sequence numbers (dropped frames counted from sequence gaps), controls.
//
// Colour tables assume fixed exposure and white balance: with automatic exposure or white
// balance the colours of a landmark drift and the table stops matching. `cyl capture
// --fixed-exposure` switches the device's auto exposure, auto white balance and auto gain
// off where the driver has those controls (see lock_auto_controls()).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "cylfe/mjpeg.hpp"
#include "cylfe/source.hpp"

namespace cylfe {

struct V4L2Options {
    std::string device = "/dev/video0";
    uint32_t fourcc = 0;        // 0 = first of YUYV, UYVY, NV12, YU12 that the device offers
    uint32_t width = 640, height = 480;
    double fps = 30.0;          // requested with VIDIOC_S_PARM (0 = leave the driver's)
    unsigned buffers = 4;       // mmap buffers requested (>= 4)
    int timeout_ms = 2000;      // a frame must arrive within this time
    int input = -1;             // VIDIOC_S_INPUT index (-1 = leave)
};

struct V4L2FormatInfo {
    uint32_t fourcc;
    std::string description;
    bool supported;                          // libcyl reads it
    std::vector<std::pair<uint32_t, uint32_t>> sizes;  // discrete sizes, or {min, max} for stepwise
    bool stepwise;
};

struct V4L2ControlInfo {
    uint32_t id;
    std::string name;
    uint32_t type;        // V4L2_CTRL_TYPE_*
    int64_t minimum, maximum, step, default_value, value;
    std::vector<std::string> menu;   // menu items (index = value) for menu controls
    bool read_only, inactive;
};

struct V4L2DeviceInfo {
    std::string path, driver, card, bus;
    bool capture;     // offers single-planar video capture with streaming
};

// The pixel format to capture: `asked` (a V4L2 fourcc, 0 = choose) among the `offered` ones.
// Chosen: the first of YUYV, UYVY, NV12, YU12 offered, else MJPG (decoded to YUYV, cylfe/mjpeg.hpp).
// Throws Error naming the device and what it offers when nothing fits.
uint32_t choose_v4l2_format(const std::vector<uint32_t> &offered, uint32_t asked, const std::string &dev);

class V4L2Source : public Source {
public:
    // Opens, checks capabilities, negotiates format, size and interval, maps buffers and starts
    // streaming. Throws Error with a message naming the device and what failed:
    // no such device, not a capture device, busy, format not offered, ...
    explicit V4L2Source(const V4L2Options &opt);
    ~V4L2Source() override;
    V4L2Source(const V4L2Source &) = delete;
    V4L2Source &operator=(const V4L2Source &) = delete;

    const StreamInfo &info() const override { return info_; }
    // Waits for the next frame (polling in short slices so that request_stop() is seen).
    // Throws Error on timeout or when the device is gone; returns false once stopped.
    bool next(SourceEvent &ev) override;
    uint64_t dropped() const override { return dropped_; }
    uint64_t frames() const { return frames_; }
    double frame_interval_s() const { return interval_s_; }

    std::vector<V4L2ControlInfo> controls() const;
    // Set a control by name (case-insensitive) or numeric id; menu controls also take item names.
    void set_control(const std::string &name_or_id, const std::string &value);
    // Turn off auto exposure, auto white balance and auto gain where present; returns what was changed.
    std::vector<std::string> lock_auto_controls();

    // Async-signal-safe: makes next() return false at its next poll slice.
    static void request_stop();
    static void clear_stop();

private:
    void stop_streaming() noexcept;
    int fd_ = -1;
    std::string dev_;
    StreamInfo info_;
    struct Buffer { void *start; size_t length; };
    std::vector<Buffer> bufs_;
    int queued_index_ = -1;     // buffer handed out by the last next(), requeued on the next call
    bool streaming_ = false;
    int timeout_ms_;
    uint64_t dropped_ = 0, frames_ = 0;
    int64_t last_seq_ = -1;
    double interval_s_ = 0;
    bool mjpeg_ = false;        // MJPG capture: frames decoded into decoded_ (YUYV)
    MjpegDecoder decoder_;
    std::vector<uint8_t> decoded_;
    uint64_t corrupt_ = 0;      // MJPG frames that did not decode (skipped, counted as dropped)
};

// Devices /dev/video* with their driver, card and whether they can capture.
std::vector<V4L2DeviceInfo> v4l2_list_devices();
// Formats and frame sizes a device offers (opens it briefly).
std::vector<V4L2FormatInfo> v4l2_list_formats(const std::string &device);
// Controls of a device (opens it briefly).
std::vector<V4L2ControlInfo> v4l2_list_controls(const std::string &device);

} // namespace cylfe
