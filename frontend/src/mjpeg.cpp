// SPDX-License-Identifier: BSD-3-Clause
#include "cylfe/mjpeg.hpp"
#include "cylfe/error.hpp"

#include <csetjmp>
#include <cstdio>
#include <cstring>

#include <jpeglib.h>

namespace cylfe {
namespace {

struct ErrorMgr {
    jpeg_error_mgr pub;
    jmp_buf jump;
    char msg[JMSG_LENGTH_MAX];
};

void on_error(j_common_ptr c)
{
    ErrorMgr *e = reinterpret_cast<ErrorMgr *>(c->err);
    (*c->err->format_message)(c, e->msg);
    std::longjmp(e->jump, 1);
}

void on_message(j_common_ptr) {}  // warnings (e.g. "premature end of data") are not printed

} // namespace

size_t yuyv_size(uint32_t w, uint32_t h) { return (size_t)w * h * 2; }

void MjpegDecoder::decode(const uint8_t *jpeg, size_t size, uint32_t width, uint32_t height, std::vector<uint8_t> &out,
                          const std::string &what)
{
    jpeg_decompress_struct ci;
    ErrorMgr err;
    ci.err = jpeg_std_error(&err.pub);
    err.pub.error_exit = on_error;
    err.pub.output_message = on_message;
    err.msg[0] = 0;
    // Only plain data lives across the setjmp: the error text is copied out before throwing.
    if (setjmp(err.jump)) {
        std::string m = err.msg;
        jpeg_destroy_decompress(&ci);
        throw Error(what + ": corrupt JPEG frame: " + m);
    }
    jpeg_create_decompress(&ci);
    jpeg_mem_src(&ci, const_cast<unsigned char *>(jpeg), (unsigned long)size);
    jpeg_read_header(&ci, TRUE);
    std::string problem;
    if (width % 2)
        problem = "is " + std::to_string(width) + " px wide: MJPG frames are read at even widths";
    else if (ci.image_width != width || ci.image_height != height)
        problem = "is " + std::to_string(ci.image_width) + "x" + std::to_string(ci.image_height) + ", not the " +
                  std::to_string(width) + "x" + std::to_string(height) + " negotiated";
    else if (ci.num_components != 3 || ci.jpeg_color_space != JCS_YCbCr)
        problem = "is not a 3-component YCbCr JPEG";
    int hs[3] = {0, 0, 0}, vs[3] = {0, 0, 0};
    if (problem.empty()) {
        for (int c = 0; c < 3; c++) { hs[c] = ci.comp_info[c].h_samp_factor; vs[c] = ci.comp_info[c].v_samp_factor; }
        const bool chroma_11 = hs[1] == 1 && vs[1] == 1 && hs[2] == 1 && vs[2] == 1;
        if (!chroma_11 || hs[0] < 1 || hs[0] > 2 || vs[0] < 1 || vs[0] > 2)
            problem = "has a chroma sampling other than 4:4:4, 4:2:2, 4:2:0 or 4:4:0";
    }
    if (!problem.empty()) {
        jpeg_destroy_decompress(&ci);
        throw Error(what + ": the JPEG frame " + problem);
    }
    sampling_ = hs[0] == 2 ? (vs[0] == 2 ? "4:2:0" : "4:2:2") : (vs[0] == 2 ? "4:4:0" : "4:4:4");
    ci.raw_data_out = TRUE;
    ci.do_fancy_upsampling = FALSE;
    ci.dct_method = JDCT_ISLOW;
    ci.out_color_space = JCS_YCbCr;
    jpeg_start_decompress(&ci);
    // Raw data: one iMCU row per call, v_samp * DCTSIZE rows of each component, each as wide as
    // the MCUs it covers.
    size_t stride[3], rows[3];
    for (int c = 0; c < 3; c++) {
        stride[c] = (size_t)ci.MCUs_per_row * (size_t)ci.comp_info[c].h_samp_factor * DCTSIZE;
        rows[c] = (size_t)ci.total_iMCU_rows * (size_t)ci.comp_info[c].v_samp_factor * DCTSIZE;
        plane_[c].resize(stride[c] * rows[c]);
    }
    std::vector<JSAMPROW> ptr[3];
    for (int c = 0; c < 3; c++) ptr[c].resize((size_t)ci.comp_info[c].v_samp_factor * DCTSIZE);
    for (JDIMENSION r = 0; r < ci.total_iMCU_rows; r++) {
        JSAMPARRAY arr[3];
        for (int c = 0; c < 3; c++) {
            const size_t n = ptr[c].size(), first = (size_t)r * n;
            for (size_t k = 0; k < n; k++) ptr[c][k] = plane_[c].data() + (first + k) * stride[c];
            arr[c] = ptr[c].data();
        }
        jpeg_read_raw_data(&ci, arr, (JDIMENSION)(ci.max_v_samp_factor * DCTSIZE));
    }
    jpeg_finish_decompress(&ci);
    jpeg_destroy_decompress(&ci);

    // To YUYV: luma as it is; each pixel pair's chroma from the source samples under it (4:2:2:
    // the sample itself; 4:2:0 and 4:4:0: the sample of its row band; 4:4:4: the pair's mean).
    out.resize(yuyv_size(width, height));
    // luma samples per chroma sample across (1 or 2, checked above) and down
    const bool half_across = hs[0] == 2;
    const uint32_t rv = vs[0] == 2 ? 2u : 1u;
    for (uint32_t y = 0; y < height; y++) {
        const uint8_t *py = &plane_[0][y * stride[0]];
        const size_t sy = y / rv;
        const uint8_t *pu = &plane_[1][sy * stride[1]], *pv = &plane_[2][sy * stride[2]];
        uint8_t *d = &out[(size_t)y * width * 2];
        for (uint32_t x = 0; x < width; x += 2) {
            unsigned u, v;
            if (half_across) {
                u = pu[x / 2];
                v = pv[x / 2];
            } else {
                u = (pu[x] + pu[x + 1] + 1u) / 2u;
                v = (pv[x] + pv[x + 1] + 1u) / 2u;
            }
            d[2 * x] = py[x];
            d[2 * x + 1] = (uint8_t)u;
            d[2 * x + 2] = py[x + 1];
            d[2 * x + 3] = (uint8_t)v;
        }
    }
}

} // namespace cylfe
