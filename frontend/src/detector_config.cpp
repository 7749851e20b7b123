// SPDX-License-Identifier: BSD-3-Clause
// The detector config file (docs/formats.md, "Detector config"): the segmentation's and the
// clutter gates' settings per class, read strictly (pipeline.hpp).
#include "cylfe/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "cylfe/error.hpp"
#include "cylfe/keys.hpp"

namespace cylfe {

namespace {

struct Reader {
    std::string path;

    std::string at(const YAML::Node &n) const { return path + ":" + std::to_string(n.Mark().line + 1); }

    [[noreturn]] void fail(const YAML::Node &n, const std::string &what) const { throw Error(at(n) + ": " + what); }

    // Keys of a mapping: duplicates and unknown keys are errors naming the nearest known one.
    void keys(const YAML::Node &m, const std::string &where, const std::vector<std::string> &known) const
    {
        if (!m.IsMap()) fail(m, where + ": expected a mapping");
        std::map<std::string, int> seen;
        for (auto it = m.begin(); it != m.end(); ++it) {
            if (!it->first.IsScalar()) fail(it->first, where + ": a key that is not a plain name");
            const std::string k = it->first.Scalar();
            const int line = it->first.Mark().line + 1;
            if (seen.count(k)) {
                std::string msg = where;
                msg += ": key '" + k + "' given twice (lines " + std::to_string(seen[k]) + " and ";
                msg += std::to_string(line) + ")";
                fail(it->first, msg);
            }
            seen[k] = line;
            if (!known.empty() && std::find(known.begin(), known.end(), k) == known.end()) {
                std::string msg = where;
                msg += ": unknown key '" + k + "'";
                msg += did_you_mean(k, known);
                fail(it->first, msg);
            }
        }
    }

    double number(const YAML::Node &n, const std::string &field, double lo, double hi, bool integer) const
    {
        double v = 0;
        if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v))
            fail(n, field + ": expected a number");
        if (v < lo || v > hi || (integer && v != std::floor(v)))
            fail(n, field + ": " + n.Scalar() + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) +
                        "]" + (integer ? " or not a whole number" : ""));
        return v;
    }

    std::vector<double> list(const YAML::Node &n, const std::string &field, size_t count, double lo, double hi,
                             bool integer) const
    {
        if (!n.IsSequence() || n.size() != count)
            fail(n, field + ": expected a list of " + std::to_string(count) + " numbers");
        std::vector<double> v;
        for (const YAML::Node &e : n) v.push_back(number(e, field, lo, hi, integer));
        return v;
    }
};

const std::vector<std::string> kTop = {"roi", "mask", "min_run_px", "split_axes", "classes", "landmarks"};
const std::vector<std::string> kLandmarks = {"plane_height_m", "grouping", "models"};
const std::vector<std::string> kGrouping = {"overlap_min", "scale_tol", "gap_slack_px", "depression_max_deg",
                                            "max_candidates"};
const std::vector<std::string> kModel = {"name", "bands", "band_heights_m", "shape", "diameter_m", "id"};
const std::vector<std::string> kClass = {"min_area_px", "max_area_px", "merge_gap_px", "merge_min_density", "size_m",
                                         "size_gate", "aspect_range", "min_fill", "split_waist",
                                         "weak_alone_min_area_px"};

void read_class(const Reader &r, const YAML::Node &n, const std::string &where, DetectorConfig &cfg, unsigned k)
{
    r.keys(n, where, kClass);
    cyl_class_params &cp = cfg.segment.cls[k];
    ClassGate &g = cfg.gate[k];
    if (n["min_area_px"]) cp.min_area = (uint32_t)r.number(n["min_area_px"], where + ".min_area_px", 0, 1e9, true);
    if (n["max_area_px"]) g.max_area_px = (uint32_t)r.number(n["max_area_px"], where + ".max_area_px", 0, 1e9, true);
    if (n["merge_gap_px"]) cp.merge_gap_px = (int32_t)r.number(n["merge_gap_px"], where + ".merge_gap_px", -1, 1000, true);
    if (n["merge_min_density"])
        cp.merge_min_density = r.number(n["merge_min_density"], where + ".merge_min_density", 0, 1, false);
    if (n["size_m"]) {
        std::vector<double> v = r.list(n["size_m"], where + ".size_m", 2, 1e-6, 1e3, false);
        cfg.observe.size[k].diameter_m = v[0];
        cfg.observe.size[k].height_m = v[1];
    }
    if (n["aspect_range"]) {
        std::vector<double> v = r.list(n["aspect_range"], where + ".aspect_range", 2, 0, 1e4, false);
        if (v[0] > v[1]) r.fail(n["aspect_range"], where + ".aspect_range: [low, high] with low <= high");
        g.aspect_min = v[0];
        g.aspect_max = v[1];
    }
    if (n["min_fill"]) g.min_fill = r.number(n["min_fill"], where + ".min_fill", 0, 1, false);
    if (n["weak_alone_min_area_px"])
        cp.weak_alone_min_area = (uint32_t)r.number(n["weak_alone_min_area_px"], where + ".weak_alone_min_area_px", 0, 1e9, true);
    if (n["split_waist"]) cfg.split.waist_ratio[k] = r.number(n["split_waist"], where + ".split_waist", 0, 1, false);
    if (n["size_gate"]) {
        g.size_gate = r.number(n["size_gate"], where + ".size_gate", 0, 100, false);
        if (g.size_gate > 0 && g.size_gate < 1) r.fail(n["size_gate"], where + ".size_gate: 0 (off) or >= 1");
    }
}

// landmarks: the band models of multi-colour landmarks (cyl/landmark.h)
void read_landmarks(const Reader &r, const YAML::Node &n, const cyl_colortable &table, DetectorConfig &cfg)
{
    r.keys(n, "landmarks", kLandmarks);
    if (!n["plane_height_m"]) r.fail(n, "landmarks: plane_height_m is required (the height above the floor of the "
                                        "plane the camera's mount_height_m is counted from, m)");
    cfg.plane_height_m = r.number(n["plane_height_m"], "landmarks.plane_height_m", 0, 100, false);
    if (n["grouping"]) {
        const YAML::Node g = n["grouping"];
        r.keys(g, "landmarks.grouping", kGrouping);
        if (g["overlap_min"]) cfg.group.overlap_min = r.number(g["overlap_min"], "landmarks.grouping.overlap_min", 0, 1, false);
        if (g["scale_tol"]) cfg.group.scale_tol = r.number(g["scale_tol"], "landmarks.grouping.scale_tol", 0, 5, false);
        if (g["gap_slack_px"])
            cfg.group.gap_slack_px = r.number(g["gap_slack_px"], "landmarks.grouping.gap_slack_px", 0, 1000, false);
        if (g["depression_max_deg"])
            cfg.group.depression_max_deg =
                r.number(g["depression_max_deg"], "landmarks.grouping.depression_max_deg", 0, 89, false);
        if (g["max_candidates"])
            cfg.group.max_candidates =
                (uint32_t)r.number(g["max_candidates"], "landmarks.grouping.max_candidates", 1, 1e6, true);
    }
    const YAML::Node ms = n["models"];
    if (!ms || !ms.IsSequence() || ms.size() == 0) r.fail(ms ? ms : n, "landmarks.models: expected a list of models");
    cfg.models.clear();
    cfg.model_names.clear();
    for (size_t i = 0; i < ms.size(); i++) {
        const YAML::Node m = ms[i];
        const std::string where = "landmarks.models[" + std::to_string(i) + "]";
        r.keys(m, where, kModel);
        for (const char *req : {"name", "bands", "band_heights_m", "diameter_m"})
            if (!m[req]) r.fail(m, where + ": " + req + " is required");
        if (!m["name"].IsScalar() || m["name"].Scalar().empty()) r.fail(m["name"], where + ".name: expected a name");
        const std::string name = m["name"].Scalar();
        for (const std::string &other : cfg.model_names)
            if (other == name) r.fail(m["name"], std::string(where).append(".name: '").append(name).append("' names two models"));
        cyl_landmark_model md{};
        md.id = -1;
        const YAML::Node bands = m["bands"];
        if (!bands.IsSequence() || bands.size() < 1 || bands.size() > CYL_MODEL_MAX_BANDS)
            r.fail(bands, where + ".bands: expected a list of 1 to " + std::to_string(CYL_MODEL_MAX_BANDS) +
                              " class names (or gap), top to bottom");
        md.n_bands = (uint8_t)bands.size();
        for (size_t k = 0; k < bands.size(); k++) {
            if (!bands[k].IsScalar()) r.fail(bands[k], where + ".bands: expected class names");
            const std::string b = bands[k].Scalar();
            if (b == "gap") {
                md.band_cls[k] = CYL_BAND_GAP;
                continue;
            }
            const int cls = cyl_colortable_find_class(&table, b.c_str());
            if (cls < 0) {
                std::vector<std::string> names = {"gap"};
                for (unsigned c = 0; c < CYL_MAX_CLASSES; c++)
                    if (table.name[c][0]) names.push_back(table.name[c]);
                r.fail(bands[k], std::string(where).append(".bands: '").append(b).append("' is not a class of the table").append(did_you_mean(b, names)));
            }
            if (table.weak_of[cls] != CYL_CLASS_NONE)
                r.fail(bands[k], std::string(where).append(".bands: '").append(b).append("' is a weak class (its pixels join its class's blobs)"));
            md.band_cls[k] = (uint8_t)cls;
        }
        std::vector<double> h = r.list(m["band_heights_m"], where + ".band_heights_m", bands.size(), 1e-4, 100, false);
        for (size_t k = 0; k < h.size(); k++) md.band_height_m[k] = h[k];
        std::string shape = "cylinder";
        if (m["shape"]) {
            if (!m["shape"].IsScalar()) r.fail(m["shape"], where + ".shape: cylinder or cone");
            shape = m["shape"].Scalar();
        }
        if (shape == "cylinder") {
            md.shape = CYL_SHAPE_CYLINDER;
            if (m["diameter_m"].IsSequence())
                r.fail(m["diameter_m"], where + ".diameter_m: a cylinder has one diameter (a cone: [base, top])");
            md.diameter_bottom_m = r.number(m["diameter_m"], where + ".diameter_m", 1e-4, 100, false);
        } else if (shape == "cone") {
            md.shape = CYL_SHAPE_CONE;
            std::vector<double> d = r.list(m["diameter_m"], where + ".diameter_m", 2, 0, 100, false);
            if (!(d[0] > 0)) r.fail(m["diameter_m"], where + ".diameter_m: the base diameter must be > 0");
            md.diameter_bottom_m = d[0];
            md.diameter_top_m = d[1];
        } else {
            r.fail(m["shape"], std::string(where).append(".shape: '").append(shape).append("' is not cylinder or cone"));
        }
        if (m["id"]) md.id = (int32_t)r.number(m["id"], where + ".id", 0, 2147483647.0, true);
        cfg.models.push_back(md);
        cfg.model_names.push_back(name);
        const cyl_status st = cyl_landmark_models_check(cfg.models.data(), (uint32_t)cfg.models.size());
        if (st != CYL_OK) {
            if (md.band_cls[0] == CYL_BAND_GAP || md.band_cls[md.n_bands - 1] == CYL_BAND_GAP)
                r.fail(bands, where + ".bands: the first and the last band must be classes, not gap");
            for (size_t j = 0; j + 1 < cfg.models.size(); j++)
                if (cfg.models[j].n_bands == md.n_bands &&
                    std::equal(md.band_cls, md.band_cls + md.n_bands, cfg.models[j].band_cls))
                    r.fail(bands, where + ".bands: the same bands as model '" + cfg.model_names[j] +
                                      "' (the code would not tell them apart)");
            r.fail(m, where + ": " + cyl_status_str(st));
        }
    }
    std::vector<int32_t> ids;
    for (size_t i = 0; i < cfg.models.size(); i++) {
        if (cfg.models[i].id < 0) continue;
        if (std::find(ids.begin(), ids.end(), cfg.models[i].id) != ids.end())
            r.fail(ms[i]["id"], "landmarks.models[" + std::to_string(i) + "].id: " + std::to_string(cfg.models[i].id) +
                                    " is the id of another model");
        ids.push_back(cfg.models[i].id);
    }
}

} // namespace

bool parse_size_option(const std::string &spec, std::string &name, cyl_landmark_size &size)
{
    const size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0) return false;
    const char *p = spec.c_str() + eq + 1;
    char *end = nullptr;
    const double d = std::strtod(p, &end);
    if (end == p || *end != ',') return false;
    p = end + 1;
    const double h = std::strtod(p, &end);
    if (end == p || *end != '\0') return false;
    if (!(d > 0 && d <= 1e3 && h > 0 && h <= 1e3)) return false;
    name = spec.substr(0, eq);
    size.diameter_m = d;
    size.height_m = h;
    return true;
}

void load_detector_config(const std::string &path, const cyl_colortable &table, DetectorConfig &cfg)
{
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path + ": cannot open detector config file");
    std::stringstream ss;
    ss << f.rdbuf();
    const std::string text = ss.str();
    if (text.size() > (1u << 20)) throw Error(path + ": not a detector config file: larger than 1 MiB");
    int depth = 0, max_depth = 0;
    for (char ch : text) {
        if (ch == '[' || ch == '{') max_depth = std::max(max_depth, ++depth);
        else if ((ch == ']' || ch == '}') && depth > 0) depth--;
    }
    if (max_depth > 8) throw Error(path + ": not a detector config file: nested more than 8 levels");
    YAML::Node root;
    try {
        root = YAML::Load(text);
    } catch (const YAML::Exception &e) {
        throw Error(path + ": not readable YAML: " + e.what());
    }
    if (root.IsNull()) return;   // an empty file: the defaults
    Reader r{path};
    r.keys(root, "top level", kTop);
    if (root["roi"]) {
        std::vector<double> v = r.list(root["roi"], "roi", 4, 0, CYL_MAX_DIM, true);
        cfg.segment.roi.x = (uint32_t)v[0];
        cfg.segment.roi.y = (uint32_t)v[1];
        cfg.segment.roi.width = (uint32_t)v[2];
        cfg.segment.roi.height = (uint32_t)v[3];
        if (v[2] == 0 || v[3] == 0) r.fail(root["roi"], "roi: width and height must be > 0");
    }
    if (root["min_run_px"]) cfg.segment.min_run_px = (uint16_t)r.number(root["min_run_px"], "min_run_px", 1, 1000, true);
    if (root["split_axes"]) {
        const YAML::Node a = root["split_axes"];
        const std::string v = a.IsScalar() ? a.Scalar() : "";
        const unsigned axes = split_axes_from_name(v);
        if (!axes) r.fail(a, "split_axes: '" + v + "' is not rows, columns or both");
        cfg.split.axes = axes;
    }
    if (root["mask"]) {
        const YAML::Node m = root["mask"];
        if (!m.IsScalar() || m.Scalar().empty()) r.fail(m, "mask: expected a file name");
        std::string mp = m.Scalar();
        size_t slash = path.find_last_of('/');
        if (mp[0] != '/' && slash != std::string::npos) mp = path.substr(0, slash + 1) + mp;
        try {
            load_detector_mask(mp, cfg);
        } catch (const Error &e) {
            throw Error(r.at(m) + ": mask: " + e.what());
        }
    }
    if (root["landmarks"]) read_landmarks(r, root["landmarks"], table, cfg);
    if (root["classes"]) {
        const YAML::Node cl = root["classes"];
        std::vector<std::string> names = {"all"};
        for (unsigned k = 0; k < CYL_MAX_CLASSES; k++)
            if (table.name[k][0]) names.push_back(table.name[k]);
        r.keys(cl, "classes", names);
        if (cl["all"])
            for (unsigned k = 0; k < CYL_MAX_CLASSES; k++) read_class(r, cl["all"], "classes.all", cfg, k);
        for (auto it = cl.begin(); it != cl.end(); ++it) {
            const std::string name = it->first.Scalar();
            if (name == "all") continue;
            read_class(r, it->second, "classes." + name, cfg, (unsigned)cyl_colortable_find_class(&table, name.c_str()));
        }
    }
}

std::string detector_config_yaml(const DetectorConfig &cfg, const cyl_colortable &table, const std::string &comment)
{
    std::string s;
    char b[256];
    if (!comment.empty()) s += "# " + comment + "\n";
    const cyl_segment_params d = cyl_segment_params_default();
    if (cfg.segment.roi.width && cfg.segment.roi.height) {
        std::snprintf(b, sizeof b, "roi: [%u, %u, %u, %u]\n", cfg.segment.roi.x, cfg.segment.roi.y, cfg.segment.roi.width,
                      cfg.segment.roi.height);
        s += b;
    }
    if (cfg.segment.min_run_px != d.min_run_px) s += "min_run_px: " + std::to_string(cfg.segment.min_run_px) + "\n";
    if (cfg.split.axes != cyl_split_params_default().axes) s += std::string("split_axes: ") + split_axes_name(cfg.split.axes) + "\n";
    std::string cls;
    for (unsigned k = 0; k < CYL_MAX_CLASSES; k++) {
        if (!table.name[k][0] || table.weak_of[k] != CYL_CLASS_NONE) continue;
        const cyl_class_params &c = cfg.segment.cls[k];
        const ClassGate &g = cfg.gate[k];
        std::string e;
        if (c.min_area != d.cls[k].min_area) e += "    min_area_px: " + std::to_string(c.min_area) + "\n";
        if (g.max_area_px) e += "    max_area_px: " + std::to_string(g.max_area_px) + "\n";
        if (c.merge_gap_px != d.cls[k].merge_gap_px) e += "    merge_gap_px: " + std::to_string(c.merge_gap_px) + "\n";
        if (c.merge_min_density != d.cls[k].merge_min_density) {
            std::snprintf(b, sizeof b, "    merge_min_density: %.3g\n", c.merge_min_density);
            e += b;
        }
        if (g.aspect_min > 0 || g.aspect_max > 0) {
            std::snprintf(b, sizeof b, "    aspect_range: [%.3g, %.3g]\n", g.aspect_min, g.aspect_max);
            e += b;
        }
        if (g.min_fill > 0) {
            std::snprintf(b, sizeof b, "    min_fill: %.3g\n", g.min_fill);
            e += b;
        }
        if (c.weak_alone_min_area) e += "    weak_alone_min_area_px: " + std::to_string(c.weak_alone_min_area) + "\n";
        if (cfg.split.waist_ratio[k] > 0) {
            std::snprintf(b, sizeof b, "    split_waist: %.3g\n", cfg.split.waist_ratio[k]);
            e += b;
        }
        if (cfg.observe.size[k].diameter_m > 0) {
            std::snprintf(b, sizeof b, "    size_m: [%.6g, %.6g]\n", cfg.observe.size[k].diameter_m, cfg.observe.size[k].height_m);
            e += b;
        }
        if (g.size_gate > 0) {
            std::snprintf(b, sizeof b, "    size_gate: %.3g\n", g.size_gate);
            e += b;
        }
        if (!e.empty()) cls += "  " + std::string(table.name[k]) + ":\n" + e;
    }
    if (!cls.empty()) s += "classes:\n" + cls;
    if (!cfg.models.empty()) {
        std::snprintf(b, sizeof b, "landmarks:\n  plane_height_m: %.6g\n  models:\n", cfg.plane_height_m);
        s += b;
        for (size_t i = 0; i < cfg.models.size(); i++) {
            const cyl_landmark_model &m = cfg.models[i];
            std::string bands, hs;
            for (int k = 0; k < m.n_bands; k++) {
                bands += (k ? ", " : "") + std::string(m.band_cls[k] == CYL_BAND_GAP ? "gap" : table.name[m.band_cls[k]]);
                std::snprintf(b, sizeof b, "%s%.6g", k ? ", " : "", m.band_height_m[k]);
                hs += b;
            }
            s.append("    - name: ").append(cfg.model_names[i]).append("\n      bands: [").append(bands);
            s.append("]\n      band_heights_m: [").append(hs).append("]\n");
            if (m.shape == CYL_SHAPE_CONE)
                std::snprintf(b, sizeof b, "      shape: cone\n      diameter_m: [%.6g, %.6g]\n", m.diameter_bottom_m,
                              m.diameter_top_m);
            else
                std::snprintf(b, sizeof b, "      diameter_m: %.6g\n", m.diameter_bottom_m);
            s += b;
            if (m.id >= 0) s += "      id: " + std::to_string(m.id) + "\n";
        }
    }
    return s;
}

} // namespace cylfe
