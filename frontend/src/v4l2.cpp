// SPDX-License-Identifier: BSD-3-Clause
// V4L2 capture. Every ioctl is checked, EINTR retried, buffers released on every exit path.
#include "cylfe/v4l2.hpp"
#include "cylfe/error.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <dirent.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace cylfe {

namespace {

volatile std::sig_atomic_t g_stop = 0;

int xioctl(int fd, unsigned long req, void *arg)
{
    int r;
    do { r = ioctl(fd, req, arg); } while (r == -1 && errno == EINTR);
    return r;
}

std::string err(const std::string &dev, const std::string &what)
{
    return dev + ": " + what + ": " + std::strerror(errno);
}

int open_device(const std::string &dev, bool nonblock)
{
    struct stat st;
    if (stat(dev.c_str(), &st) == -1) {
        if (errno == ENOENT) throw Error(dev + ": no such device");
        throw Error(err(dev, "cannot access"));
    }
    if (!S_ISCHR(st.st_mode)) throw Error(dev + ": not a device (not a character special file)");
    int fd;
    do { fd = open(dev.c_str(), O_RDWR | (nonblock ? O_NONBLOCK : 0)); } while (fd == -1 && errno == EINTR);
    if (fd == -1) {
        if (errno == EBUSY) throw Error(dev + ": device busy (in use by another program)");
        if (errno == ENODEV || errno == ENXIO) throw Error(dev + ": no such device (driver not present)");
        throw Error(err(dev, "cannot open"));
    }
    return fd;
}

struct FdGuard {
    int fd;
    ~FdGuard() { if (fd >= 0) close(fd); }
};

uint32_t caps_of(const v4l2_capability &cap)
{
    return (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
}

std::string lower(std::string s)
{
    for (char &c : s) c = (char)std::tolower((unsigned char)c);
    return s;
}

std::vector<V4L2ControlInfo> query_controls(int fd)
{
    std::vector<V4L2ControlInfo> out;
    v4l2_queryctrl q;
    std::memset(&q, 0, sizeof q);
    q.id = V4L2_CTRL_FLAG_NEXT_CTRL;
    while (xioctl(fd, VIDIOC_QUERYCTRL, &q) == 0) {
        if (!(q.flags & V4L2_CTRL_FLAG_DISABLED) && q.type != V4L2_CTRL_TYPE_CTRL_CLASS) {
            V4L2ControlInfo c;
            c.id = q.id;
            c.name = reinterpret_cast<const char *>(q.name);
            c.type = q.type;
            c.minimum = q.minimum;
            c.maximum = q.maximum;
            c.step = q.step;
            c.default_value = q.default_value;
            c.read_only = q.flags & V4L2_CTRL_FLAG_READ_ONLY;
            c.inactive = q.flags & V4L2_CTRL_FLAG_INACTIVE;
            c.value = 0;
            if (q.type == V4L2_CTRL_TYPE_INTEGER || q.type == V4L2_CTRL_TYPE_BOOLEAN ||
                q.type == V4L2_CTRL_TYPE_MENU || q.type == V4L2_CTRL_TYPE_INTEGER_MENU) {
                v4l2_control v = {q.id, 0};
                if (xioctl(fd, VIDIOC_G_CTRL, &v) == 0) c.value = v.value;
            }
            if (q.type == V4L2_CTRL_TYPE_MENU) {
                for (int64_t i = 0; i <= q.maximum; i++) {
                    v4l2_querymenu m;
                    std::memset(&m, 0, sizeof m);
                    m.id = q.id;
                    m.index = (uint32_t)i;
                    c.menu.push_back(xioctl(fd, VIDIOC_QUERYMENU, &m) == 0 ? reinterpret_cast<const char *>(m.name) : "");
                }
            }
            out.push_back(c);
        }
        q.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
    }
    return out;
}

void set_control_fd(int fd, const std::string &dev, const std::string &name_or_id, const std::string &value)
{
    std::vector<V4L2ControlInfo> ctrls = query_controls(fd);
    const V4L2ControlInfo *c = nullptr;
    char *end = nullptr;
    unsigned long id = std::strtoul(name_or_id.c_str(), &end, 0);
    for (const auto &k : ctrls)
        if ((end && *end == 0 && k.id == id) || lower(k.name) == lower(name_or_id)) c = &k;
    if (!c) throw Error(dev + ": no control named '" + name_or_id + "' (see --list-controls)");
    int64_t v = 0;
    bool found = false;
    for (size_t i = 0; i < c->menu.size(); i++)
        if (!c->menu[i].empty() && lower(c->menu[i]) == lower(value)) { v = (int64_t)i; found = true; }
    if (!found) {
        char *e = nullptr;
        v = std::strtoll(value.c_str(), &e, 0);
        if (value.empty() || (e && *e)) throw Error(dev + ": control '" + c->name + "': bad value '" + value + "'");
    }
    if (c->type != V4L2_CTRL_TYPE_BUTTON && (v < c->minimum || v > c->maximum))
        throw Error(dev + ": control '" + c->name + "': value " + std::to_string(v) + " outside " +
                    std::to_string(c->minimum) + ".." + std::to_string(c->maximum));
    v4l2_control s = {c->id, (int32_t)v};
    if (xioctl(fd, VIDIOC_S_CTRL, &s) == -1) throw Error(err(dev, "cannot set control '" + c->name + "'"));
}

const uint32_t kPreferred[] = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_UYVY, V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_YUV420};

std::vector<uint32_t> offered_formats(int fd)
{
    std::vector<uint32_t> out;
    v4l2_fmtdesc d;
    std::memset(&d, 0, sizeof d);
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    while (xioctl(fd, VIDIOC_ENUM_FMT, &d) == 0) {
        out.push_back(d.pixelformat);
        d.index++;
    }
    return out;
}

} // namespace

uint32_t choose_v4l2_format(const std::vector<uint32_t> &offered, uint32_t asked, const std::string &dev)
{
    auto has = [&](uint32_t f) { return std::find(offered.begin(), offered.end(), f) != offered.end(); };
    std::string list;
    for (uint32_t p : offered) list += " " + fourcc_str(p);
    if (list.empty()) list = " nothing";
    if (asked == 0) {
        for (uint32_t p : kPreferred)
            if (has(p)) return p;
        if (has(V4L2_PIX_FMT_MJPEG)) return V4L2_PIX_FMT_MJPEG;
        throw Error(dev + ": offers none of YUYV, UYVY, NV12, YU12 or MJPG (the device offers:" + list + ")");
    }
    if (asked != V4L2_PIX_FMT_MJPEG && pixfmt_from_fourcc(asked) == 0)
        throw Error(dev + ": libcyl cannot read pixel format " + fourcc_str(asked) + " (YUYV, UYVY, NV12, YU12 or MJPG)");
    if (!has(asked)) throw Error(dev + ": format " + fourcc_str(asked) + " not offered (the device offers:" + list + ")");
    return asked;
}

void V4L2Source::request_stop() { g_stop = 1; }
void V4L2Source::clear_stop() { g_stop = 0; }

V4L2Source::V4L2Source(const V4L2Options &opt) : dev_(opt.device), timeout_ms_(opt.timeout_ms)
{
    if (opt.buffers < 4) throw Error(dev_ + ": at least 4 buffers are needed, " + std::to_string(opt.buffers) + " asked");
    fd_ = open_device(dev_, true);
    try {
        v4l2_capability cap;
        std::memset(&cap, 0, sizeof cap);
        if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) == -1) {
            if (errno == ENOTTY || errno == EINVAL) throw Error(dev_ + ": not a V4L2 device");
            throw Error(err(dev_, "VIDIOC_QUERYCAP"));
        }
        uint32_t caps = caps_of(cap);
        if (!(caps & V4L2_CAP_VIDEO_CAPTURE))
            throw Error(dev_ + ": not a video capture device (driver " + reinterpret_cast<const char *>(cap.driver) + ")");
        if (!(caps & V4L2_CAP_STREAMING)) throw Error(dev_ + ": the driver does not support streaming I/O");
        if (opt.input >= 0) {
            int in = opt.input;
            if (xioctl(fd_, VIDIOC_S_INPUT, &in) == -1) throw Error(err(dev_, "cannot select input " + std::to_string(in)));
        }

        // Pixel format: the one asked for, or the first libcyl reads (a YUV layout, else MJPG).
        const uint32_t want = choose_v4l2_format(offered_formats(fd_), opt.fourcc, dev_);
        mjpeg_ = want == V4L2_PIX_FMT_MJPEG;
        v4l2_format fmt;
        std::memset(&fmt, 0, sizeof fmt);
        fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        fmt.fmt.pix.width = opt.width;
        fmt.fmt.pix.height = opt.height;
        fmt.fmt.pix.pixelformat = want;
        fmt.fmt.pix.field = V4L2_FIELD_NONE;
        if (xioctl(fd_, VIDIOC_S_FMT, &fmt) == -1) {
            if (errno == EBUSY) throw Error(dev_ + ": device busy (streaming in another program)");
            throw Error(err(dev_, "VIDIOC_S_FMT"));
        }
        if (fmt.fmt.pix.pixelformat != want)
            throw Error(dev_ + ": format " + fourcc_str(want) + " not accepted (driver chose " +
                        fourcc_str(fmt.fmt.pix.pixelformat) + ")");
        if (fmt.fmt.pix.width != opt.width || fmt.fmt.pix.height != opt.height)
            throw Error(dev_ + ": size " + std::to_string(opt.width) + "x" + std::to_string(opt.height) +
                        " not offered (driver chose " + std::to_string(fmt.fmt.pix.width) + "x" +
                        std::to_string(fmt.fmt.pix.height) + ")");
        // MJPG frames are decoded to YUYV: the stream carries that layout from here on.
        cyl_pixfmt pf = mjpeg_ ? CYL_FMT_YUYV : pixfmt_from_fourcc(want);
        info_.fourcc = mjpeg_ ? fourcc_from_pixfmt(CYL_FMT_YUYV) : want;
        info_.width = fmt.fmt.pix.width;
        info_.height = fmt.fmt.pix.height;
        info_.stride = mjpeg_ ? 2 * fmt.fmt.pix.width : fmt.fmt.pix.bytesperline;
        info_.frame_bytes = (uint32_t)cyl_image_buffer_size(pf, info_.width, info_.height, info_.stride);
        if (info_.frame_bytes == 0 || (!mjpeg_ && info_.frame_bytes > fmt.fmt.pix.sizeimage))
            throw Error(dev_ + ": driver layout (bytesperline " + std::to_string(info_.stride) + ", sizeimage " +
                        std::to_string(fmt.fmt.pix.sizeimage) + ") is not the contiguous layout libcyl reads");
        info_.source = std::string(mjpeg_ ? "v4l2 mjpg " : "v4l2 ") + reinterpret_cast<const char *>(cap.driver);

        // Frame interval.
        v4l2_streamparm parm;
        std::memset(&parm, 0, sizeof parm);
        parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (opt.fps > 0 && xioctl(fd_, VIDIOC_G_PARM, &parm) == 0 &&
            (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
            parm.parm.capture.timeperframe.numerator = 1000;
            parm.parm.capture.timeperframe.denominator = (uint32_t)std::lround(opt.fps * 1000.0);
            if (xioctl(fd_, VIDIOC_S_PARM, &parm) == -1) throw Error(err(dev_, "VIDIOC_S_PARM"));
        }
        std::memset(&parm, 0, sizeof parm);
        parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (xioctl(fd_, VIDIOC_G_PARM, &parm) == 0 && parm.parm.capture.timeperframe.denominator)
            interval_s_ = (double)parm.parm.capture.timeperframe.numerator / parm.parm.capture.timeperframe.denominator;

        // Buffers.
        v4l2_requestbuffers req;
        std::memset(&req, 0, sizeof req);
        req.count = opt.buffers;
        req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        req.memory = V4L2_MEMORY_MMAP;
        if (xioctl(fd_, VIDIOC_REQBUFS, &req) == -1) {
            if (errno == EBUSY) throw Error(dev_ + ": device busy (buffers owned by another program)");
            throw Error(err(dev_, "VIDIOC_REQBUFS"));
        }
        if (req.count < 4) throw Error(dev_ + ": driver granted only " + std::to_string(req.count) + " buffers");
        for (uint32_t i = 0; i < req.count; i++) {
            v4l2_buffer b;
            std::memset(&b, 0, sizeof b);
            b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            b.memory = V4L2_MEMORY_MMAP;
            b.index = i;
            if (xioctl(fd_, VIDIOC_QUERYBUF, &b) == -1) throw Error(err(dev_, "VIDIOC_QUERYBUF"));
            void *p = mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
            if (p == MAP_FAILED) throw Error(err(dev_, "mmap"));
            bufs_.push_back({p, b.length});
        }
        for (uint32_t i = 0; i < bufs_.size(); i++) {
            v4l2_buffer b;
            std::memset(&b, 0, sizeof b);
            b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            b.memory = V4L2_MEMORY_MMAP;
            b.index = i;
            if (xioctl(fd_, VIDIOC_QBUF, &b) == -1) throw Error(err(dev_, "VIDIOC_QBUF"));
        }
        v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (xioctl(fd_, VIDIOC_STREAMON, &type) == -1) throw Error(err(dev_, "VIDIOC_STREAMON"));
        streaming_ = true;
    } catch (...) {
        stop_streaming();
        throw;
    }
}

void V4L2Source::stop_streaming() noexcept
{
    if (fd_ < 0) return;
    if (streaming_) {
        v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        xioctl(fd_, VIDIOC_STREAMOFF, &type);  // may fail when the device is gone: nothing more to do
        streaming_ = false;
    }
    for (const Buffer &b : bufs_) munmap(b.start, b.length);
    bufs_.clear();
    if (fd_ >= 0) {
        v4l2_requestbuffers req;
        std::memset(&req, 0, sizeof req);
        req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        req.memory = V4L2_MEMORY_MMAP;
        xioctl(fd_, VIDIOC_REQBUFS, &req);  // release the driver's buffers
        close(fd_);
    }
    fd_ = -1;
}

V4L2Source::~V4L2Source() { stop_streaming(); }

bool V4L2Source::next(SourceEvent &ev)
{
    if (fd_ < 0) return false;
    if (queued_index_ >= 0) {  // give the previous frame's buffer back to the driver
        v4l2_buffer b;
        std::memset(&b, 0, sizeof b);
        b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        b.memory = V4L2_MEMORY_MMAP;
        b.index = (uint32_t)queued_index_;
        queued_index_ = -1;
        if (xioctl(fd_, VIDIOC_QBUF, &b) == -1) {
            if (errno == ENODEV) throw Error(dev_ + ": device disconnected");
            throw Error(err(dev_, "VIDIOC_QBUF"));
        }
    }
    int waited = 0;
    for (;;) {
        if (g_stop) return false;
        pollfd p = {fd_, POLLIN, 0};
        int slice = std::min(100, timeout_ms_ - waited);
        int r = poll(&p, 1, slice < 1 ? 1 : slice);
        if (r == -1) {
            if (errno == EINTR) continue;  // a signal: g_stop is checked at the top
            throw Error(err(dev_, "poll"));
        }
        if (r == 0) {
            waited += slice;
            if (waited >= timeout_ms_)
                throw Error(dev_ + ": timeout: no frame within " + std::to_string(timeout_ms_) + " ms");
            continue;
        }
        bool poll_error = p.revents & (POLLERR | POLLHUP | POLLNVAL);
        v4l2_buffer b;
        std::memset(&b, 0, sizeof b);
        b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        b.memory = V4L2_MEMORY_MMAP;
        if (xioctl(fd_, VIDIOC_DQBUF, &b) == -1) {
            // vivid's "Disconnect" and a USB unplug: poll reports an error and DQBUF ENODEV.
            if (errno == ENODEV || errno == EPIPE) throw Error(dev_ + ": device disconnected");
            if (errno == EAGAIN && !poll_error) continue;
            if (errno == EAGAIN) throw Error(dev_ + ": device error (poll reported an error, no buffer ready)");
            if (errno == EIO) throw Error(dev_ + ": I/O error from the driver");
            throw Error(err(dev_, "VIDIOC_DQBUF"));
        }
        if (b.index >= bufs_.size()) throw Error(dev_ + ": driver returned an unknown buffer index");
        queued_index_ = (int)b.index;
        if (mjpeg_) {
            // Decode now, then hand the buffer straight back: a corrupt frame (USB cameras do send
            // them) is skipped and counted as dropped, not the end of the run.
            bool ok = b.bytesused > 0 && !(b.flags & V4L2_BUF_FLAG_ERROR);
            if (ok) {
                try {
                    decoder_.decode(static_cast<const uint8_t *>(bufs_[b.index].start),
                                    std::min<size_t>(b.bytesused, bufs_[b.index].length), info_.width, info_.height,
                                    decoded_, dev_ + ": frame " + std::to_string(b.sequence));
                } catch (const Error &) {
                    ok = false;
                }
            }
            if (xioctl(fd_, VIDIOC_QBUF, &b) == -1) {
                if (errno == ENODEV) throw Error(dev_ + ": device disconnected");
                throw Error(err(dev_, "VIDIOC_QBUF"));
            }
            queued_index_ = -1;
            if (!ok) {  // counted as dropped by the sequence gap at the next good frame
                corrupt_++;
                continue;
            }
        } else if (b.bytesused && b.bytesused < info_.frame_bytes)
            throw Error(dev_ + ": short frame (" + std::to_string(b.bytesused) + " of " +
                        std::to_string(info_.frame_bytes) + " bytes)");
        if (last_seq_ >= 0 && (int64_t)b.sequence > last_seq_ + 1) dropped_ += (uint64_t)((int64_t)b.sequence - last_seq_ - 1);
        last_seq_ = b.sequence;
        frames_++;
        ev.kind = RecordType::Frame;
        ev.header.type = RecordType::Frame;
        ev.header.seq = b.sequence;
        ev.header.t_ns = (int64_t)b.timestamp.tv_sec * 1000000000LL + (int64_t)b.timestamp.tv_usec * 1000LL;
        ev.header.size = info_.frame_bytes;
        ev.header.flags = (b.flags & V4L2_BUF_FLAG_ERROR) ? 1u : 0u;
        if ((b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC)
            info_.flags |= StreamInfo::kMonotonic;
        ev.data = mjpeg_ ? decoded_.data() : static_cast<const uint8_t *>(bufs_[b.index].start);
        check(cyl_image_wrap(&ev.image, pixfmt_from_fourcc(info_.fourcc), info_.width, info_.height, ev.data, info_.stride),
              dev_ + ": frame layout");
        return true;
    }
}

std::vector<V4L2ControlInfo> V4L2Source::controls() const { return query_controls(fd_); }

void V4L2Source::set_control(const std::string &name_or_id, const std::string &value)
{
    set_control_fd(fd_, dev_, name_or_id, value);
}

std::vector<std::string> V4L2Source::lock_auto_controls()
{
    std::vector<std::string> changed;
    for (const auto &c : query_controls(fd_)) {
        if (c.read_only) continue;
        if (c.id == V4L2_CID_EXPOSURE_AUTO && c.value != V4L2_EXPOSURE_MANUAL) {
            v4l2_control s = {c.id, V4L2_EXPOSURE_MANUAL};
            if (xioctl(fd_, VIDIOC_S_CTRL, &s) == 0) changed.push_back(c.name + " = manual");
        } else if ((c.id == V4L2_CID_AUTO_WHITE_BALANCE || c.id == V4L2_CID_AUTOGAIN) && c.value != 0) {
            v4l2_control s = {c.id, 0};
            if (xioctl(fd_, VIDIOC_S_CTRL, &s) == 0) changed.push_back(c.name + " = off");
        }
    }
    return changed;
}

std::vector<V4L2DeviceInfo> v4l2_list_devices()
{
    std::vector<V4L2DeviceInfo> out;
    DIR *d = opendir("/dev");
    if (!d) return out;
    std::vector<std::string> names;
    while (dirent *e = readdir(d))
        if (std::strncmp(e->d_name, "video", 5) == 0) names.push_back(std::string("/dev/") + e->d_name);
    closedir(d);
    std::sort(names.begin(), names.end());
    for (const std::string &n : names) {
        int fd = open(n.c_str(), O_RDWR | O_NONBLOCK);
        if (fd < 0) continue;
        FdGuard g{fd};
        v4l2_capability cap;
        std::memset(&cap, 0, sizeof cap);
        if (xioctl(fd, VIDIOC_QUERYCAP, &cap) == -1) continue;
        uint32_t caps = caps_of(cap);
        out.push_back({n, reinterpret_cast<const char *>(cap.driver), reinterpret_cast<const char *>(cap.card),
                       reinterpret_cast<const char *>(cap.bus_info),
                       (caps & V4L2_CAP_VIDEO_CAPTURE) && (caps & V4L2_CAP_STREAMING)});
    }
    return out;
}

std::vector<V4L2FormatInfo> v4l2_list_formats(const std::string &device)
{
    FdGuard g{open_device(device, true)};
    std::vector<V4L2FormatInfo> out;
    v4l2_fmtdesc d;
    std::memset(&d, 0, sizeof d);
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    while (xioctl(g.fd, VIDIOC_ENUM_FMT, &d) == 0) {
        V4L2FormatInfo f;
        f.fourcc = d.pixelformat;
        f.description = reinterpret_cast<const char *>(d.description);
        f.supported = pixfmt_from_fourcc(d.pixelformat) != 0;
        f.stepwise = false;
        v4l2_frmsizeenum s;
        std::memset(&s, 0, sizeof s);
        s.pixel_format = d.pixelformat;
        while (xioctl(g.fd, VIDIOC_ENUM_FRAMESIZES, &s) == 0) {
            if (s.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
                f.sizes.push_back({s.discrete.width, s.discrete.height});
            } else {
                f.stepwise = true;
                f.sizes.push_back({s.stepwise.min_width, s.stepwise.min_height});
                f.sizes.push_back({s.stepwise.max_width, s.stepwise.max_height});
                break;
            }
            s.index++;
        }
        out.push_back(f);
        d.index++;
    }
    if (out.empty() && errno != EINVAL) throw Error(err(device, "VIDIOC_ENUM_FMT"));
    return out;
}

std::vector<V4L2ControlInfo> v4l2_list_controls(const std::string &device)
{
    FdGuard g{open_device(device, true)};
    return query_controls(g.fd);
}

} // namespace cylfe
