// SPDX-License-Identifier: BSD-3-Clause
#include "cylfe/rawlog.hpp"
#include "cylfe/error.hpp"

#include <cerrno>
#include <cstring>
#include <sys/stat.h>

namespace cylfe {

namespace {

constexpr char kMagic[8] = {'C', 'Y', 'L', 'R', 'A', 'W', 0, 0};
constexpr char kRecMagic[4] = {'R', 'E', 'C', '1'};
constexpr uint32_t kVersion = 1, kHeaderSize = 64, kRecHeaderSize = 32;

void put32(uint8_t *p, uint32_t v) { for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i)); }
void put64(uint8_t *p, uint64_t v) { for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i)); }
uint32_t get32(const uint8_t *p) { uint32_t v = 0; for (int i = 3; i >= 0; i--) v = (v << 8) | p[i]; return v; }
uint64_t get64(const uint8_t *p) { uint64_t v = 0; for (int i = 7; i >= 0; i--) v = (v << 8) | p[i]; return v; }
void putd(uint8_t *p, double d) { uint64_t u; std::memcpy(&u, &d, 8); put64(p, u); }
double getd(const uint8_t *p) { uint64_t u = get64(p); double d; std::memcpy(&d, &u, 8); return d; }

std::string errno_text() { return std::strerror(errno); }

} // namespace

uint32_t fourcc_from_pixfmt(cyl_pixfmt f)
{
    switch (f) {
    case CYL_FMT_YUYV: return fourcc('Y', 'U', 'Y', 'V');
    case CYL_FMT_UYVY: return fourcc('U', 'Y', 'V', 'Y');
    case CYL_FMT_NV12: return fourcc('N', 'V', '1', '2');
    case CYL_FMT_I420: return fourcc('Y', 'U', '1', '2');
    case CYL_FMT_YUV444P: return fourcc('4', '4', '4', 'P');
    }
    return 0;
}

cyl_pixfmt pixfmt_from_fourcc(uint32_t fcc)
{
    for (cyl_pixfmt f : {CYL_FMT_YUYV, CYL_FMT_UYVY, CYL_FMT_NV12, CYL_FMT_I420, CYL_FMT_YUV444P})
        if (fourcc_from_pixfmt(f) == fcc) return f;
    return (cyl_pixfmt)0;
}

std::string fourcc_str(uint32_t fcc)
{
    std::string s;
    for (int i = 0; i < 4; i++) {
        char c = (char)((fcc >> (8 * i)) & 0xFF);
        s += (c >= 32 && c < 127) ? c : '?';
    }
    return s;
}

// ---- writer -------------------------------------------------------------------------

RawLogWriter::RawLogWriter(const std::string &path, const StreamInfo &info)
    : path_(path), plan_(plan_output(path)), info_(info)
{
    part_ = plan_.write_to;
    if (pixfmt_from_fourcc(info.fourcc) == 0)
        throw Error(path + ": unsupported pixel format " + fourcc_str(info.fourcc));
    f_ = std::fopen(part_.c_str(), "wb");
    if (!f_) throw Error(part_ + ": cannot create: " + errno_text());
    uint8_t h[kHeaderSize] = {0};
    std::memcpy(h, kMagic, 8);
    put32(h + 8, kVersion);
    put32(h + 12, kHeaderSize);
    put32(h + 16, info.fourcc);
    put32(h + 20, info.width);
    put32(h + 24, info.height);
    put32(h + 28, info.stride);
    put32(h + 32, info.frame_bytes);
    put32(h + 36, info.flags);
    std::strncpy(reinterpret_cast<char *>(h + 40), info.source.c_str(), 23);
    if (std::fwrite(h, 1, sizeof h, f_) != sizeof h || std::fflush(f_) != 0) {
        std::fclose(f_);
        f_ = nullptr;
        throw Error(part_ + ": write failed: " + errno_text());
    }
}

RawLogWriter::~RawLogWriter()
{
    // Not closed explicitly (an exception is unwinding): keep the complete records in .part.
    if (f_) std::fclose(f_);
}

void RawLogWriter::record(RecordType type, uint64_t seq, int64_t t_ns, const void *payload, uint32_t n,
                          uint32_t flags)
{
    if (!f_) throw Error(path_ + ": write after close");
    uint8_t h[kRecHeaderSize];
    std::memcpy(h, kRecMagic, 4);
    put32(h + 4, (uint32_t)type);
    put64(h + 8, seq);
    put64(h + 16, (uint64_t)t_ns);
    put32(h + 24, n);
    put32(h + 28, flags);
    if (std::fwrite(h, 1, sizeof h, f_) != sizeof h || (n && std::fwrite(payload, 1, n, f_) != n) ||
        std::fflush(f_) != 0)
        throw Error(part_ + ": write failed: " + errno_text());
    records_++;
}

void RawLogWriter::frame(uint64_t seq, int64_t t_ns, const uint8_t *data, size_t n, uint32_t flags)
{
    if (n != info_.frame_bytes)
        throw Error(path_ + ": frame " + std::to_string(seq) + " has " + std::to_string(n) +
                    " bytes, the stream's frames have " + std::to_string(info_.frame_bytes));
    record(RecordType::Frame, seq, t_ns, data, (uint32_t)n, flags);
}

void RawLogWriter::odometry(uint64_t seq, int64_t t_ns, const Odometry &o)
{
    uint8_t p[9 * 8];
    putd(p, o.dx_m); putd(p + 8, o.dy_m); putd(p + 16, o.dtheta_rad);
    for (int i = 0; i < 6; i++) putd(p + 24 + 8 * i, o.cov[i]);
    record(RecordType::Odometry, seq, t_ns, p, sizeof p, 0);
}

void RawLogWriter::truth_pose(uint64_t seq, int64_t t_ns, const TruthPose &t)
{
    uint8_t p[3 * 8];
    putd(p, t.x_m); putd(p + 8, t.y_m); putd(p + 16, t.theta_rad);
    record(RecordType::TruthPose, seq, t_ns, p, sizeof p, 0);
}

void RawLogWriter::truth_landmark(int64_t t_ns, const TruthLandmark &l)
{
    uint8_t p[8 + 4 * 8];
    put32(p, l.id); put32(p + 4, l.cls);
    putd(p + 8, l.x_m); putd(p + 16, l.y_m); putd(p + 24, l.diameter_m); putd(p + 32, l.height_m);
    record(RecordType::TruthLandmark, 0, t_ns, p, sizeof p, 0);
}

void RawLogWriter::close()
{
    if (!f_) return;
    int bad = std::fflush(f_) != 0;
    bad |= std::fclose(f_) != 0;
    f_ = nullptr;
    if (bad) throw Error(part_ + ": write failed: " + errno_text());
    finish_output(plan_);
}

// ---- reader -------------------------------------------------------------------------

RawLogReader::RawLogReader(const std::string &path) : path_(path)
{
    f_ = std::fopen(path.c_str(), "rb");
    if (!f_) throw Error(path + ": cannot open: " + errno_text());
    struct stat st;
    if (fstat(fileno(f_), &st) == 0) size_ = (uint64_t)st.st_size;
    uint8_t h[kHeaderSize];
    size_t got = std::fread(h, 1, sizeof h, f_);
    if (got < 12 || std::memcmp(h, kMagic, 8) != 0) {
        std::fclose(f_);
        f_ = nullptr;
        throw Error(path + ": not a libcyl raw frame log (bad magic)");
    }
    uint32_t version = get32(h + 8);
    if (version != kVersion) {
        std::fclose(f_);
        f_ = nullptr;
        throw Error(path + ": raw log version " + std::to_string(version) + " is not supported (this build reads 1)");
    }
    if (got < sizeof h || get32(h + 12) != kHeaderSize) {
        std::fclose(f_);
        f_ = nullptr;
        throw Error(path + ": truncated or malformed header");
    }
    info_.fourcc = get32(h + 16);
    info_.width = get32(h + 20);
    info_.height = get32(h + 24);
    info_.stride = get32(h + 28);
    info_.frame_bytes = get32(h + 32);
    info_.flags = get32(h + 36);
    info_.source.assign(reinterpret_cast<const char *>(h + 40), strnlen(reinterpret_cast<const char *>(h + 40), 24));
    cyl_pixfmt fmt = pixfmt_from_fourcc(info_.fourcc);
    size_t need = fmt ? cyl_image_buffer_size(fmt, info_.width, info_.height, info_.stride) : 0;
    std::string why;
    if (!fmt) why = "pixel format " + fourcc_str(info_.fourcc) + " is not supported";
    else if (need == 0) why = "invalid frame size " + std::to_string(info_.width) + "x" + std::to_string(info_.height) +
                              " stride " + std::to_string(info_.stride);
    else if (need != info_.frame_bytes) why = "frame size field " + std::to_string(info_.frame_bytes) +
                                             " does not match the format (" + std::to_string(need) + " bytes)";
    if (!why.empty()) {
        std::fclose(f_);
        f_ = nullptr;
        throw Error(path + ": header field: " + why);
    }
    offset_ = kHeaderSize;
}

RawLogReader::~RawLogReader()
{
    if (f_) std::fclose(f_);
}

void RawLogReader::rewind()
{
    std::fseek(f_, (long)kHeaderSize, SEEK_SET);
    offset_ = kHeaderSize;
    truncated_ = false;
}

bool RawLogReader::next(RecordHeader &h, std::vector<uint8_t> &payload)
{
    uint8_t b[kRecHeaderSize];
    size_t got = std::fread(b, 1, sizeof b, f_);
    if (got == 0) return false;
    if (got < sizeof b) { truncated_ = true; return false; }
    if (std::memcmp(b, kRecMagic, 4) != 0)
        throw Error(path_ + ": corrupt record header at byte " + std::to_string(offset_));
    h.type = (RecordType)get32(b + 4);
    h.seq = get64(b + 8);
    h.t_ns = (int64_t)get64(b + 16);
    h.size = get32(b + 24);
    h.flags = get32(b + 28);
    uint32_t t = (uint32_t)h.type;
    uint32_t expect = t == 1 ? info_.frame_bytes : t == 2 ? 72u : t == 3 ? 24u : t == 4 ? 40u : h.size;
    if (h.size != expect || h.size > (1u << 30))
        throw Error(path_ + ": record at byte " + std::to_string(offset_) + " (type " + std::to_string(t) +
                    ") has payload size " + std::to_string(h.size) + ", expected " + std::to_string(expect));
    payload.resize(h.size);
    if (h.size && std::fread(payload.data(), 1, h.size, f_) != h.size) { truncated_ = true; return false; }
    offset_ += sizeof b + h.size;
    return true;
}

Odometry RawLogReader::parse_odometry(const std::vector<uint8_t> &p)
{
    Odometry o;
    o.dx_m = getd(&p[0]); o.dy_m = getd(&p[8]); o.dtheta_rad = getd(&p[16]);
    for (int i = 0; i < 6; i++) o.cov[i] = getd(&p[24 + 8 * i]);
    return o;
}

TruthPose RawLogReader::parse_truth_pose(const std::vector<uint8_t> &p)
{
    TruthPose t;
    t.x_m = getd(&p[0]); t.y_m = getd(&p[8]); t.theta_rad = getd(&p[16]);
    return t;
}

TruthLandmark RawLogReader::parse_truth_landmark(const std::vector<uint8_t> &p)
{
    TruthLandmark l;
    l.id = get32(&p[0]); l.cls = get32(&p[4]);
    l.x_m = getd(&p[8]); l.y_m = getd(&p[16]); l.diameter_m = getd(&p[24]); l.height_m = getd(&p[32]);
    return l;
}

} // namespace cylfe
