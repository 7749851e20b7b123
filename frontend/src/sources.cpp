// SPDX-License-Identifier: BSD-3-Clause
#include "cylfe/sources.hpp"
#include "cylfe/error.hpp"

#include <chrono>
#include <thread>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>  // cv::CAP_PROP_* only: reading is in the media plugin

#include "cylfe/media.hpp"

namespace cylfe {

namespace {
int64_t now_ns()
{
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}
bool ends_with(const std::string &s, const std::string &e)
{
    return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}
} // namespace

// ---- raw log replay ---------------------------------------------------------------------

RawLogSource::RawLogSource(const std::string &path, bool realtime) : reader_(path), realtime_(realtime) {}

double RawLogSource::progress() const
{
    return reader_.file_size() ? (double)reader_.offset() / (double)reader_.file_size() : -1.0;
}

bool RawLogSource::next(SourceEvent &ev)
{
    RecordHeader h;
    for (;;) {
        if (!reader_.next(h, payload_)) return false;
        ev.header = h;
        ev.kind = h.type;
        switch (h.type) {
        case RecordType::Frame: {
            const StreamInfo &in = reader_.info();
            ev.data = payload_.data();
            check(cyl_image_wrap(&ev.image, pixfmt_from_fourcc(in.fourcc), in.width, in.height, ev.data, in.stride),
                  "raw log frame");
            if (realtime_) {
                if (!started_) { started_ = true; first_t_ = h.t_ns; wall0_ = now_ns(); }
                int64_t due = wall0_ + (h.t_ns - first_t_), now = now_ns();
                if (due > now) std::this_thread::sleep_for(std::chrono::nanoseconds(due - now));
            }
            return true;
        }
        case RecordType::Odometry: ev.odometry = RawLogReader::parse_odometry(payload_); return true;
        case RecordType::TruthPose: ev.truth_pose = RawLogReader::parse_truth_pose(payload_); return true;
        case RecordType::TruthLandmark: ev.truth_landmark = RawLogReader::parse_truth_landmark(payload_); return true;
        default: continue;  // unknown record types are skipped (forward compatibility)
        }
    }
}

// ---- image and video files --------------------------------------------------------------

struct FileSource::Impl {
    std::vector<std::string> paths;
    size_t next_path = 0;
    media::VideoReader video;
    bool is_video = false;
    double frames_total = 0, frames_done = 0, fps = 30;
    cv::Mat bgr, yuv;
    uint64_t seq = 0;
};

static bool is_video_path(const std::string &p)
{
    for (const char *e : {".avi", ".mp4", ".mkv", ".mov", ".webm", ".mjpeg", ".m4v"})
        if (ends_with(p, e)) return true;
    return false;
}

FileSource::FileSource(const std::vector<std::string> &paths, double fps) : impl_(new Impl)
{
    if (paths.empty()) throw Error("file source: no files given");
    impl_->paths = paths;
    impl_->fps = fps > 0 ? fps : 30;
    if (paths.size() == 1 && is_video_path(paths[0])) {
        impl_->is_video = true;
        if (!impl_->video.open(paths[0])) throw Error(paths[0] + ": cannot open video");
        impl_->frames_total = impl_->video.get(cv::CAP_PROP_FRAME_COUNT);
        double f = impl_->video.get(cv::CAP_PROP_FPS);
        if (f > 0) impl_->fps = f;
        if (!impl_->video.read(impl_->bgr) || impl_->bgr.empty()) throw Error(paths[0] + ": no frame in video");
    } else {
        impl_->bgr = media::imread(paths[0], cv::IMREAD_COLOR);
        if (impl_->bgr.empty()) throw Error(paths[0] + ": cannot read image");
        impl_->frames_total = (double)paths.size();
    }
    int w = impl_->bgr.cols & ~1, h = impl_->bgr.rows & ~1;
    if (w < 2 || h < 2) throw Error(paths[0] + ": image too small");
    info_.fourcc = fourcc_from_pixfmt(CYL_FMT_I420);
    info_.width = (uint32_t)w;
    info_.height = (uint32_t)h;
    info_.stride = (uint32_t)w;
    info_.frame_bytes = (uint32_t)cyl_image_buffer_size(CYL_FMT_I420, info_.width, info_.height, 0);
    info_.source = "file";
}

FileSource::~FileSource() = default;

double FileSource::progress() const
{
    return impl_->frames_total > 0 ? impl_->frames_done / impl_->frames_total : -1.0;
}

bool FileSource::next(SourceEvent &ev)
{
    Impl &m = *impl_;
    if (m.is_video) {
        if (m.frames_done > 0 && (!m.video.read(m.bgr) || m.bgr.empty())) return false;
    } else {
        if (m.next_path >= m.paths.size()) return false;
        if (m.next_path > 0) {
            m.bgr = media::imread(m.paths[m.next_path], cv::IMREAD_COLOR);
            if (m.bgr.empty()) throw Error(m.paths[m.next_path] + ": cannot read image");
        }
        m.next_path++;
    }
    cv::Mat crop = m.bgr(cv::Rect(0, 0, (int)info_.width, (int)info_.height));
    if (m.bgr.cols < (int)info_.width || m.bgr.rows < (int)info_.height)
        throw Error("file source: frame " + std::to_string(m.seq) + " is smaller than the first");
    cv::cvtColor(crop, m.yuv, cv::COLOR_BGR2YUV_I420);
    m.frames_done++;
    ev.kind = RecordType::Frame;
    ev.header.type = RecordType::Frame;
    ev.header.seq = m.seq;
    ev.header.t_ns = (int64_t)((double)m.seq * 1e9 / m.fps);
    ev.header.size = info_.frame_bytes;
    ev.header.flags = 0;
    ev.data = m.yuv.data;
    m.seq++;
    check(cyl_image_wrap(&ev.image, CYL_FMT_I420, info_.width, info_.height, ev.data, 0), "file frame");
    return true;
}

// ---- factory ----------------------------------------------------------------------------

std::unique_ptr<Source> make_synthetic_source(const SourceOptions &opt);  // synth_source.cpp

std::unique_ptr<Source> open_source(const std::string &spec, const SourceOptions &opt)
{
    auto after = [&](const char *prefix) { return spec.substr(std::string(prefix).size()); };
    if (spec.rfind("v4l2:", 0) == 0 || spec.rfind("/dev/video", 0) == 0) {
        V4L2Options o = opt.v4l2;
        o.device = spec.rfind("v4l2:", 0) == 0 ? after("v4l2:") : spec;
        return std::unique_ptr<Source>(new V4L2Source(o));
    }
    if (spec.rfind("raw:", 0) == 0) return std::unique_ptr<Source>(new RawLogSource(after("raw:"), opt.realtime));
    if (ends_with(spec, ".cylraw")) return std::unique_ptr<Source>(new RawLogSource(spec, opt.realtime));
    if (spec == "synthetic" || spec.rfind("synthetic:", 0) == 0) {
        SourceOptions o = opt;
        if (spec != "synthetic") {
            std::string s = after("synthetic:");
            char *end = nullptr;
            o.seed = std::strtoull(s.c_str(), &end, 10);
            if (s.empty() || *end) throw Error("source '" + spec + "': the seed must be a number");
        }
        return make_synthetic_source(o);
    }
    std::string path = spec.rfind("file:", 0) == 0 ? after("file:") : spec;
    return std::unique_ptr<Source>(new FileSource({path}));
}

} // namespace cylfe
