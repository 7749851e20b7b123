// SPDX-License-Identifier: BSD-3-Clause
#include "cylfe/pipeline.hpp"
#include "cylfe/error.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>  // cv::IMREAD_* only: the reading is in the media plugin

#include "cylfe/media.hpp"
#include <yaml-cpp/yaml.h>

#include "cylfe/keys.hpp"

namespace cylfe {

// ---- names --------------------------------------------------------------------------

const char *model_name(cyl_geom_model m) { return m == CYL_GEOM_PAPER ? "paper" : "exact"; }

const char *estimator_name(cyl_noise_estimator e)
{
    switch (e) {
    case CYL_NOISE_UNIFORM: return "uniform";
    case CYL_NOISE_COLUMN: return "column";
    case CYL_NOISE_LOCAL: return "local";
    case CYL_NOISE_IMAGE: return "image";
    }
    return "?";
}

bool parse_model(const std::string &s, cyl_geom_model *m)
{
    if (s == "exact") { *m = CYL_GEOM_EXACT; return true; }
    if (s == "paper") { *m = CYL_GEOM_PAPER; return true; }
    return false;
}

bool parse_estimator(const std::string &s, cyl_noise_estimator *e)
{
    if (s == "uniform") { *e = CYL_NOISE_UNIFORM; return true; }
    if (s == "column") { *e = CYL_NOISE_COLUMN; return true; }
    if (s == "local") { *e = CYL_NOISE_LOCAL; return true; }
    if (s == "image") { *e = CYL_NOISE_IMAGE; return true; }
    return false;
}

// ---- detector -------------------------------------------------------------------------

Detector::Detector(const cyl_colortable &table, const cyl_camera &camera, const DetectorConfig &config)
    : table_(table), camera_(camera), config_(config)
{
    check(cyl_camera_check(&camera_), "camera");
    size_t n = cyl_segment_mem_size(config_.max_runs, config_.max_blobs);
    if (n == 0) throw Error("detector: run/blob capacities too large");
    seg_mem_.resize(n);
    check(cyl_segmentation_init(&seg_, seg_mem_.data(), seg_mem_.size(), config_.max_runs, config_.max_blobs),
          "detector: segmentation memory");
    obs_.resize(config_.max_observations);
}

uint32_t model_classes(const DetectorConfig &cfg)
{
    uint32_t m = 0;
    for (const cyl_landmark_model &md : cfg.models)
        for (int k = 0; k < md.n_bands; k++)
            if (md.band_cls[k] != CYL_BAND_GAP) m |= 1u << md.band_cls[k];
    return m;
}

const std::vector<cyl_observation> &Detector::process(const cyl_image &img)
{
    cyl_status s = cyl_segment(&table_, &img, &config_.segment, &seg_);
    check(s, "segmentation");
    truncated_ = s == CYL_TRUNCATED;
    s = split_blobs(config_, seg_, split_work_);
    check(s, "splitting blobs");
    truncated_ = truncated_ || s == CYL_TRUNCATED;
    // The image estimator reads the frame and the table (and the segmentation's own parameters,
    // recorded in seg_).
    config_.observe.image = &img;
    config_.observe.table = &table_;
    size_t need = cyl_observe_work_size(&seg_, &config_.observe);
    if (obs_work_.size() < need) obs_work_.resize(need);  // grows to the largest frame seen, once
    obs_.resize(config_.max_observations);
    const uint32_t grouped = config_.models.empty() ? 0u : model_classes(config_);
    const uint8_t mask_keep = config_.observe.class_mask;
    config_.observe.class_mask = (uint8_t)(mask_keep & ~grouped);
    uint32_t n = 0, n_single = 0;
    s = cyl_observe(&seg_, &camera_, &config_.observe, obs_work_.data(), obs_work_.size(), obs_.data(),
                    (uint32_t)obs_.size(), &n_single);
    config_.observe.class_mask = mask_keep;
    if (s < 0) config_.observe.image = nullptr;
    check(s, "observation");
    truncated_ = truncated_ || s == CYL_TRUNCATED;
    n = n_single;
    if (grouped) {
        const size_t gw = cyl_group_work_size(seg_.n_blobs, &config_.group);
        if (group_work_.size() < gw) group_work_.resize(gw);
        groups_.resize(seg_.n_blobs > 0 ? seg_.n_blobs : 1);
        uint32_t ng = 0, no = 0;
        s = cyl_group_blobs(&seg_, config_.models.data(), (uint32_t)config_.models.size(), &config_.group,
                            group_work_.data(), group_work_.size(), groups_.data(), (uint32_t)groups_.size(), &ng);
        if (s < 0) config_.observe.image = nullptr;
        check(s, "grouping");
        truncated_ = truncated_ || s == CYL_TRUNCATED;
        groups_.resize(ng);
        s = cyl_observe_groups(&seg_, groups_.data(), ng, config_.models.data(), (uint32_t)config_.models.size(),
                               config_.plane_height_m, &camera_, &config_.observe, obs_work_.data(),
                               obs_work_.size(), obs_.data() + n, (uint32_t)obs_.size() - n, &no);
        if (s < 0) config_.observe.image = nullptr;
        check(s, "observation of grouped landmarks");
        truncated_ = truncated_ || s == CYL_TRUNCATED;
        n += no;
    }
    config_.observe.image = nullptr;   // the frame is the caller's, valid during this call only
    obs_.resize(n);
    // clutter gates
    const bool masked = !config_.mask.empty();
    if (masked && (config_.mask_width != img.width || config_.mask_height != img.height))
        throw Error("detector: the mask is " + std::to_string(config_.mask_width) + "x" +
                    std::to_string(config_.mask_height) + " px but the frame is " + std::to_string(img.width) + "x" +
                    std::to_string(img.height) + " px");
    size_t k = 0;
    boxes_.clear();
    members_.clear();
    // each grouped observation's group, by its first blob (a blob is in one group at most)
    group_of_blob_.assign(grouped ? seg_.n_blobs : 0, CYL_NONE);
    for (size_t g = 0; g < groups_.size() && grouped; g++)
        for (uint32_t bb : groups_[g].blob)
            if (bb < seg_.n_blobs) group_of_blob_[bb] = (uint32_t)g;
    for (size_t i = 0; i < obs_.size(); i++) {
        const cyl_observation &o = obs_[i];
        const cyl_blob &b = seg_.blobs[o.blob];
        std::array<uint16_t, 4> box{b.x0, b.y0, b.x1, b.y1};
        std::array<uint32_t, CYL_MODEL_MAX_BANDS> members;
        members.fill(CYL_NONE);
        members[0] = o.blob;
        bool keep;
        if (o.model != CYL_NO_MODEL) {
            const cyl_group &g = groups_[group_of_blob_[o.blob]];
            box = {g.x0, g.y0, g.x1, g.y1};
            std::copy(g.blob, g.blob + CYL_MODEL_MAX_BANDS, members.begin());
            // only the mask applies: the per-class gates judge one-colour blobs
            keep = mask_keeps(config_, o.centroid_u_px, o.centroid_v_px, img.width, img.height);
        } else {
            const ClassGate &g = config_.gate[o.cls];
            keep = blob_passes(config_, b, img.width, img.height);
            if (keep && g.size_gate > 0 && o.w_est_px > 0 && o.h_est_px > 0) {
                const double f = g.size_gate;
                const bool edge = (b.flags & CYL_BLOB_TOUCH_ANY) != 0;
                if (o.w_px > f * o.w_est_px && o.h_px > f * o.h_est_px) keep = false;
                if (!edge && o.w_px * f < o.w_est_px && o.h_px * f < o.h_est_px) keep = false;
            }
        }
        if (keep) {
            obs_[k++] = o;
            boxes_.push_back(box);
            members_.push_back(members);
        } else {
            rejected_++;
        }
    }
    obs_.resize(k);
    return obs_;
}

cyl_status split_blobs(const DetectorConfig &cfg, cyl_segmentation &seg, std::vector<uint8_t> &work)
{
    const size_t need = cyl_segment_split_work_size(&seg);
    if (work.size() < need) work.resize(need);
    return cyl_segment_split(&seg, &cfg.split, work.data(), work.size(), nullptr);
}

unsigned split_axes_from_name(const std::string &name)
{
    if (name == "rows") return CYL_SPLIT_ROWS;
    if (name == "columns") return CYL_SPLIT_COLUMNS;
    if (name == "both") return CYL_SPLIT_ROWS | CYL_SPLIT_COLUMNS;
    return 0;
}

const char *split_axes_name(unsigned axes)
{
    return axes == CYL_SPLIT_ROWS ? "rows" : axes == CYL_SPLIT_COLUMNS ? "columns" : "both";
}

bool blob_passes(const DetectorConfig &cfg, const cyl_blob &b, uint32_t frame_width, uint32_t frame_height)
{
    const ClassGate &g = cfg.gate[b.cls];
    if (g.max_area_px && b.area > g.max_area_px) return false;
    const double w = (double)(b.x1 - b.x0 + 1u), h = (double)(b.y1 - b.y0 + 1u);
    // A blob cut by the frame's left or right edge is at least as wide as it looks (its true
    // aspect is no smaller), one cut at the top or bottom at least as tall (no larger): each
    // side of the gate applies where the cut cannot have caused the failure.
    const bool width_cut = (b.flags & (CYL_BLOB_TOUCH_LEFT | CYL_BLOB_TOUCH_RIGHT)) != 0;
    const bool height_cut = (b.flags & (CYL_BLOB_TOUCH_TOP | CYL_BLOB_TOUCH_BOTTOM)) != 0;
    if (g.aspect_min > 0 && !width_cut && w < g.aspect_min * h) return false;
    if (g.aspect_max > 0 && !height_cut && w > g.aspect_max * h) return false;
    if (g.min_fill > 0 && (double)b.area < g.min_fill * w * h) return false;
    return mask_keeps(cfg, b.cx_px, b.cy_px, frame_width, frame_height);
}

bool mask_keeps(const DetectorConfig &cfg, double x_px, double y_px, uint32_t frame_width, uint32_t frame_height)
{
    if (cfg.mask.empty() || cfg.mask_width != frame_width || cfg.mask_height != frame_height) return true;
    const long x = std::lround(x_px), y = std::lround(y_px);
    return !(x >= 0 && y >= 0 && x < (long)frame_width && y < (long)frame_height &&
             cfg.mask[(size_t)y * frame_width + (size_t)x] == 0);
}

void load_detector_mask(const std::string &path, DetectorConfig &cfg)
{
    cv::Mat m = media::imread(path, cv::IMREAD_GRAYSCALE);
    if (m.empty()) throw Error(path + ": cannot read the mask image");
    cfg.mask.assign(m.total(), 0);
    for (int y = 0; y < m.rows; y++)
        for (int x = 0; x < m.cols; x++) cfg.mask[(size_t)y * m.cols + x] = m.at<uint8_t>(y, x) ? 1 : 0;
    cfg.mask_width = (uint32_t)m.cols;
    cfg.mask_height = (uint32_t)m.rows;
}

// ---- observation log ------------------------------------------------------------------

namespace {

// A JSON number; non-finite values become null (JSON has no NaN). 10 significant digits for
// measurements; 17 (exact round trip) where a reader re-checks a matrix's definiteness.
std::string num(double v, int digits = 10)
{
    if (!std::isfinite(v)) return "null";
    char b[40];
    std::snprintf(b, sizeof b, "%.*g", digits, v);
    return b;
}

std::string str(const std::string &s)
{
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') { o += '\\'; o += c; }
        else if ((unsigned char)c < 0x20) { char b[8]; std::snprintf(b, sizeof b, "\\u%04x", c); o += b; }
        else o += c;
    }
    return o + "\"";
}

// The 8x8 prior covariance of (fx fy cx cy tilt yaw h s), row-major.
std::string calib_cov_json(const cyl_camera &c)
{
    double cc[CYL_CALIB_COUNT][CYL_CALIB_COUNT];
    cyl_calib_cov(&c, cc);
    std::string o;
    for (int i = 0; i < CYL_CALIB_COUNT; i++)
        for (int j = 0; j < CYL_CALIB_COUNT; j++) {
            if (i || j) o += ",";
            o += num(cc[i][j], 17);  // a rank-deficient block must stay PSD after printing
        }
    return o;
}

std::string t_sec(int64_t t_ns)
{
    char b[40];
    std::snprintf(b, sizeof b, "%.9f", (double)t_ns * 1e-9);
    return b;
}

} // namespace

ObservationLog::ObservationLog(const std::string &path, const Header &h)
    : path_(path), table_(h.table), model_names_(h.model_names)
{
    if (path == "-") {
        f_ = stdout;
        is_stdout_ = true;
    } else {
        plan_ = plan_output(path);
        part_ = plan_.write_to;
        f_ = std::fopen(part_.c_str(), "w");
        if (!f_) throw Error(part_ + ": cannot create: " + std::strerror(errno));
    }
    std::string line = "{\"type\":\"header\",\"format\":\"cyl-observations\",\"version\":2,\"source\":" + str(h.source) +
                       ",\"model\":" + str(h.model) + ",\"estimator\":" + str(h.estimator) + ",\"classes\":[";
    for (int i = 0; i < CYL_MAX_CLASSES; i++) {
        if (i) line += ",";
        line += str(h.table ? h.table->name[i] : "");
    }
    line += "]";
    if (!h.model_names.empty()) {
        line += ",\"landmark_models\":[";
        for (size_t i = 0; i < h.model_names.size(); i++) line += (i ? "," : "") + str(h.model_names[i]);
        line += "]";
    }
    if (h.camera) {
        const cyl_camera &c = *h.camera;
        line += ",\"camera\":{\"width\":" + std::to_string(c.width) + ",\"height\":" + std::to_string(c.height) +
                ",\"fx\":" + num(c.fx_px) + ",\"fy\":" + num(c.fy_px) + ",\"cx\":" + num(c.cx_px) +
                ",\"cy\":" + num(c.cy_px) + ",\"k1\":" + num(c.k1, 17) + ",\"k2\":" + num(c.k2, 17) +
                ",\"p1\":" + num(c.p1, 17) + ",\"p2\":" + num(c.p2, 17) + ",\"k3\":" + num(c.k3, 17) +
                ",\"tilt_rad\":" + num(c.tilt_rad) + ",\"yaw_rad\":" + num(c.yaw_rad) +
                ",\"height_m\":" + num(c.height_m) + ",\"offset_m\":" + num(c.offset_m) +
                ",\"calib_cov\":[" + calib_cov_json(c) + "]}";
    }
    write(line + "}");
}

ObservationLog::~ObservationLog()
{
    if (f_ && !is_stdout_) std::fclose(f_);  // not closed: keep the .part file
}

void ObservationLog::write(const std::string &line)
{
    if (!f_) throw Error(path_ + ": write after close");
    if (std::fputs(line.c_str(), f_) < 0 || std::fputc('\n', f_) == EOF)
        throw Error((is_stdout_ ? std::string("stdout") : part_) + ": write failed: " + std::strerror(errno));
    lines_++;
}

namespace {

// One JSON object on one line, built by appending (no temporaries per field).
class JsonLine {
public:
    explicit JsonLine(const char *type) { s_.reserve(512); s_ += "{\"type\":\""; s_ += type; s_ += '"'; }
    JsonLine &num(const char *key, double v) { k(key); s_ += ::cylfe::num(v); return *this; }
    JsonLine &integer(const char *key, uint64_t v) { k(key); s_ += std::to_string(v); return *this; }
    JsonLine &raw(const char *key, const std::string &v) { k(key); s_ += v; return *this; }
    JsonLine &text(const char *key, const std::string &v) { k(key); s_ += str(v); return *this; }
    const std::string &done() { s_ += '}'; return s_; }

private:
    void k(const char *key) { s_ += ",\""; s_ += key; s_ += "\":"; }
    std::string s_;
};

} // namespace

void ObservationLog::frame(uint64_t seq, int64_t t_ns, const std::vector<cyl_observation> &obs,
                           const std::vector<std::array<uint16_t, 4>> *boxes)
{
    const std::string t = t_sec(t_ns);
    write(JsonLine("frame").integer("seq", seq).raw("t", t).integer("n_obs", obs.size()).done());
    for (size_t i = 0; i < obs.size(); i++) {
        const cyl_observation &o = obs[i];
        JsonLine l("obs");
        l.integer("seq", seq).raw("t", t).text("class", table_ ? table_->name[o.cls] : std::to_string(o.cls));
        l.integer("class_id", o.cls).num("range_m", o.range_m).num("bearing_rad", o.bearing_rad);
        l.num("cov_rr", o.cov_rb[0][0]).num("cov_rb", o.cov_rb[0][1]).num("cov_bb", o.cov_rb[1][1]);
        l.num("x_m", o.x_m).num("y_m", o.y_m);
        l.num("cov_xx", o.cov_xy[0][0]).num("cov_xy", o.cov_xy[0][1]).num("cov_yy", o.cov_xy[1][1]);
        l.num("confidence", o.confidence).num("u_px", o.u_px).num("v_px", o.v_px);
        l.num("var_u_px2", o.var_u_px2).num("var_v_px2", o.var_v_px2);
        l.integer("area_px", o.area).integer("flags", o.flags);
        if (o.aspect_rel > 0.0) l.num("aspect_rel", o.aspect_rel);
        if (o.area_rel > 0.0) l.num("area_rel", o.area_rel).num("offset_rel", o.offset_rel);
        if (o.side_colour_rel != 0.0) l.num("side_colour_rel", o.side_colour_rel);
        if (boxes && i < boxes->size()) {
            const std::array<uint16_t, 4> &b = (*boxes)[i];
            l.raw("bbox_px", "[" + std::to_string(b[0]) + "," + std::to_string(b[1]) + "," + std::to_string(b[2]) + "," +
                                 std::to_string(b[3]) + "]");
        }
        if (o.model != CYL_NO_MODEL) {
            l.text("landmark_model", o.model < model_names_.size() ? model_names_[o.model] : std::to_string(o.model));
            if (o.landmark_id >= 0) l.integer("landmark_id", (uint64_t)o.landmark_id);
            l.num("code_confidence", o.code_confidence).integer("group_flags", o.group_flags);
            l.num("z_ref_m", o.z_ref_m);
        }
        std::string jm = "[", cf = "[";
        for (int a = 0; a < 2; a++)
            for (int k = 0; k < CYL_CALIB_COUNT; k++) {
                if (a || k) jm += ",";
                jm += num(o.jac_calib[a][k]);
            }
        cf += num(o.cov_rb_frame[0][0]);
        cf += ",";
        cf += num(o.cov_rb_frame[0][1]);
        cf += ",";
        cf += num(o.cov_rb_frame[1][1]);
        l.raw("jac_calib", jm + "]").raw("cov_frame", cf + "]");
        l.raw("bias_var_px2", "[" + num(o.bias_var_u_px2) + "," + num(o.bias_var_v_px2) + "]");
        if (o.subpixel_du_px != 0.0 || o.subpixel_dv_px != 0.0)
            l.raw("subpixel_shift_px", "[" + num(o.subpixel_du_px) + "," + num(o.subpixel_dv_px) + "]");
        write(l.done());
    }
    std::fflush(f_);
}

void ObservationLog::odometry(uint64_t seq, int64_t t_ns, const Odometry &o)
{
    std::string cov;
    for (int i = 0; i < 6; i++) {
        if (i) cov += ",";
        cov += num(o.cov[i]);
    }
    write("{\"type\":\"odom\",\"seq\":" + std::to_string(seq) + ",\"t\":" + t_sec(t_ns) + ",\"dx_m\":" + num(o.dx_m) +
          ",\"dy_m\":" + num(o.dy_m) + ",\"dtheta_rad\":" + num(o.dtheta_rad) + ",\"cov\":[" + cov + "]}");
    std::fflush(f_);
}

void ObservationLog::truth_pose(uint64_t seq, int64_t t_ns, const TruthPose &p)
{
    write("{\"type\":\"truth_pose\",\"seq\":" + std::to_string(seq) + ",\"t\":" + t_sec(t_ns) + ",\"x_m\":" +
          num(p.x_m) + ",\"y_m\":" + num(p.y_m) + ",\"theta_rad\":" + num(p.theta_rad) + "}");
    std::fflush(f_);
}

void ObservationLog::truth_landmark(const TruthLandmark &l)
{
    std::string name = table_ && l.cls < CYL_MAX_CLASSES ? table_->name[l.cls] : std::to_string(l.cls);
    write("{\"type\":\"truth_landmark\",\"id\":" + std::to_string(l.id) + ",\"class\":" + str(name) +
          ",\"class_id\":" + std::to_string(l.cls) + ",\"x_m\":" + num(l.x_m) + ",\"y_m\":" + num(l.y_m) +
          ",\"diameter_m\":" + num(l.diameter_m) + ",\"height_m\":" + num(l.height_m) + "}");
    std::fflush(f_);
}

void ObservationLog::close()
{
    if (!f_) return;
    if (is_stdout_) { std::fflush(f_); f_ = nullptr; return; }
    int bad = std::fflush(f_) != 0;
    bad |= std::fclose(f_) != 0;
    f_ = nullptr;
    if (bad) throw Error(part_ + ": write failed: " + std::strerror(errno));
    finish_output(plan_);
}

std::string json_quote(const std::string &s) { return str(s); }

} // namespace cylfe
