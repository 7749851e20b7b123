# SPDX-License-Identifier: BSD-3-Clause
"""cffi build script of the `cyl` Python package: compiles libcyl's C sources into the extension
cyl._cyl (API mode). Why cffi: libcyl is a plain C99 API of structs and functions with caller-owned
memory, which cffi binds from C declarations alone, checked against the real headers by the C
compiler (a struct declared here with `...;` takes its layout from the header, so no field offset
is written twice), with no C++ toolchain and no per-Python-version wrapper code (nanobind's
strength, C++ classes, is not needed here)."""
import glob
import os

from cffi import FFI

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
INC = os.path.join(ROOT, "libcyl", "include")
SRC = sorted(glob.glob(os.path.join(ROOT, "libcyl", "src", "*.c")))

ffibuilder = FFI()
ffibuilder.cdef("""
typedef int cyl_status;
typedef uint8_t cyl_mask;
#define CYL_MAX_CLASSES 8
#define CYL_CLASS_NAME_LEN 16
#define CYL_TABLE_FILE_MAX_SIZE 197036
#define CYL_OBS_NO_RANGE ...
#define CYL_OBS_INVALID ...
#define CYL_OBS_NONLINEAR ...
#define CYL_MAX_DIM ...
const char *cyl_status_str(cyl_status s);
const char *cyl_version(void);

typedef enum cyl_pixfmt { CYL_FMT_YUYV = 1, CYL_FMT_UYVY = 2, CYL_FMT_NV12 = 3, CYL_FMT_I420 = 4,
                          CYL_FMT_YUV444P = 5 } cyl_pixfmt;
typedef struct cyl_image { cyl_pixfmt format; uint32_t width; uint32_t height; const uint8_t *plane[3];
                           size_t stride[3]; } cyl_image;
typedef struct cyl_roi { uint32_t x; uint32_t y; uint32_t width; uint32_t height; } cyl_roi;
cyl_status cyl_image_wrap(cyl_image *img, cyl_pixfmt format, uint32_t width, uint32_t height,
                          const uint8_t *data, size_t stride);
size_t cyl_image_buffer_size(cyl_pixfmt format, uint32_t width, uint32_t height, size_t stride);

typedef struct cyl_colortable { char name[8][16]; uint8_t rgb[8][3]; uint8_t weak_of[8]; ...; } cyl_colortable;
void cyl_colortable_init(cyl_colortable *t);
cyl_status cyl_colortable_set_class(cyl_colortable *t, unsigned cls, const char *name, uint8_t r, uint8_t g, uint8_t b);
int cyl_colortable_find_class(const cyl_colortable *t, const char *name);
cyl_status cyl_colortable_add_box(cyl_colortable *t, unsigned cls, uint8_t y_lo, uint8_t y_hi, uint8_t u_lo,
                                  uint8_t u_hi, uint8_t v_lo, uint8_t v_hi);
cyl_mask cyl_colortable_mask(const cyl_colortable *t, uint8_t Y, uint8_t U, uint8_t V);
cyl_status cyl_colortable_save(const cyl_colortable *t, uint8_t *buf, size_t cap, size_t *len);
cyl_status cyl_colortable_load(cyl_colortable *t, const uint8_t *buf, size_t len);

typedef struct cyl_class_params { uint32_t min_area; int32_t merge_gap_px; double merge_min_density; ...; } cyl_class_params;
typedef struct cyl_segment_params { uint16_t min_run_px; uint16_t x_step; uint16_t y_step; cyl_roi roi;
                                    cyl_class_params cls[8]; ...; } cyl_segment_params;
typedef struct cyl_blob { uint8_t cls; uint8_t flags; uint16_t n_components; uint16_t x0, y0, x1, y1; uint32_t area;
                          double cx_px; double cy_px; double mxx_px2; double myy_px2; double mxy_px2;
                          double orientation_rad; double elongation; ...; } cyl_blob;
typedef struct cyl_segmentation { uint32_t n_runs; cyl_blob *blobs; uint32_t n_blobs; uint32_t truncated; ...; } cyl_segmentation;
cyl_segment_params cyl_segment_params_default(void);
uint32_t cyl_segment_max_runs(uint32_t width, uint32_t height, const cyl_segment_params *p);
size_t cyl_segment_mem_size(uint32_t max_runs, uint32_t max_blobs);
cyl_status cyl_segmentation_init(cyl_segmentation *seg, void *mem, size_t mem_size, uint32_t max_runs, uint32_t max_blobs);
cyl_status cyl_segment(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params *p, cyl_segmentation *seg);

typedef struct cyl_camera { uint32_t width; uint32_t height; double fx_px; double fy_px; double cx_px; double cy_px;
                            double k1; double k2; double p1; double p2; double k3; double tilt_rad; double yaw_rad;
                            double height_m; double offset_m; double tilt_sigma_rad; double yaw_sigma_rad;
                            double height_sigma_m; double offset_sigma_m; double intr_cov[9][9]; uint32_t flags;
                            ...; } cyl_camera;
#define CYL_CAM_INTR_COV_UNKNOWN ...
#define CYL_CAM_EXTR_SIG_UNKNOWN ...
void cyl_camera_init(cyl_camera *cam);
void cyl_camera_set_intrinsic_sigmas(cyl_camera *cam, const double sigma[9]);
cyl_status cyl_camera_check(const cyl_camera *cam);

typedef enum cyl_noise_estimator { CYL_NOISE_UNIFORM = 0, CYL_NOISE_COLUMN = 1, CYL_NOISE_LOCAL = 2,
                                   CYL_NOISE_IMAGE = 3 } cyl_noise_estimator;
typedef enum cyl_geom_model { CYL_GEOM_EXACT = ..., CYL_GEOM_PAPER = ... } cyl_geom_model;
typedef struct cyl_landmark_size { double diameter_m; double height_m; } cyl_landmark_size;
typedef struct cyl_observe_params { cyl_noise_estimator estimator; cyl_geom_model model; double min_var_px2;
                                    cyl_landmark_size size[8]; const cyl_image *image;
                                    const cyl_colortable *table; int subpixel; ...; } cyl_observe_params;
typedef struct cyl_observation { uint32_t blob; uint8_t cls; uint32_t flags; uint32_t area; double u_px; double v_px;
                                 double var_u_px2; double var_v_px2; double range_m; double bearing_rad;
                                 double cov_rb[2][2]; double x_m; double y_m; double cov_xy[2][2];
                                 double confidence; double aspect_rel; double area_rel; double offset_rel; double side_colour_rel; double jac_calib[2][8]; double cov_rb_frame[2][2];
                                 double bias_var_u_px2; double bias_var_v_px2; double subpixel_du_px;
                                 double subpixel_dv_px; ...; } cyl_observation;
cyl_observe_params cyl_observe_params_default(void);
cyl_observe_params cyl_observe_params_default_frame(void);
size_t cyl_observe_work_size(const cyl_segmentation *seg, const cyl_observe_params *p);
cyl_status cyl_observe(const cyl_segmentation *seg, const cyl_camera *cam, const cyl_observe_params *p, void *work,
                       size_t work_size, cyl_observation *out, uint32_t cap, uint32_t *n_out);

#define CYL_IN_COUNT ...
void cyl_rb_inputs(const cyl_camera *cam, double u_px, double v_px, double in[]);
cyl_status cyl_rb_eval(const double in[], cyl_geom_model model, double out[2], double xy[2], double jac[][15],
                       double jac_xy[][15]);
""")
ffibuilder.set_source(
    "cyl._cyl",
    '#include "cyl/status.h"\n#include "cyl/version.h"\n#include "cyl/image.h"\n#include "cyl/colortable.h"\n'
    '#include "cyl/segment.h"\n#include "cyl/camera.h"\n#include "cyl/observe.h"\n#include "cyl/rangebearing.h"\n',
    # under pip: paths relative to the repository (setuptools wants relative ones; its objects go
    # to its own build folder); in place (CYL_CFFI_TMPDIR, python/run_tests.sh): absolute, so
    # that the objects land under that folder and never beside the sources
    sources=SRC if os.environ.get("CYL_CFFI_TMPDIR") else [os.path.relpath(s, os.getcwd()) for s in SRC],
    include_dirs=[INC, os.path.join(ROOT, "libcyl", "src")],
    libraries=["m"],
    extra_compile_args=["-std=c99", "-O2"],
)

if __name__ == "__main__":
    # in place, for the tests: CYL_CFFI_TMPDIR/cyl/_cyl*.so
    ffibuilder.compile(tmpdir=os.environ.get("CYL_CFFI_TMPDIR", "."), verbose=False)
