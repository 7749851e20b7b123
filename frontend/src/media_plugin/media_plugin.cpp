// SPDX-License-Identifier: BSD-3-Clause
// libcyl-media.so: OpenCV's imgcodecs, videoio and highgui behind the interface of
// cylfe/media.hpp, so that the tools link them only when they are used (loaded with dlopen).
#include "cylfe/media.hpp"

#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

namespace {

bool imread(const std::string &path, int flags, cv::Mat &out)
{
    out = cv::imread(path, flags);
    return !out.empty();
}
bool imwrite(const std::string &path, const cv::Mat &img) { return cv::imwrite(path, img); }
bool imencode_png(const cv::Mat &img, std::vector<uint8_t> &out) { return cv::imencode(".png", img, out); }

void *video_open(const std::string &path)
{
    auto *v = new cv::VideoCapture;
    if (!v->open(path)) {
        delete v;
        return nullptr;
    }
    return v;
}
bool video_read(void *v, cv::Mat &out) { return static_cast<cv::VideoCapture *>(v)->read(out) && !out.empty(); }
double video_get(void *v, int prop) { return static_cast<cv::VideoCapture *>(v)->get(prop); }
void video_close(void *v) { delete static_cast<cv::VideoCapture *>(v); }

void *writer_open(const std::string &path, int fourcc, double fps, cv::Size size)
{
    auto *w = new cv::VideoWriter;
    if (!w->open(path, fourcc, fps, size)) {
        delete w;
        return nullptr;
    }
    return w;
}
void writer_write(void *w, const cv::Mat &img) { static_cast<cv::VideoWriter *>(w)->write(img); }
void writer_close(void *w)
{
    auto *v = static_cast<cv::VideoWriter *>(w);
    v->release();
    delete v;
}

void imshow(const std::string &win, const cv::Mat &img) { cv::imshow(win, img); }
int wait_key(int ms) { return cv::waitKey(ms); }
void named_window(const std::string &win, int flags) { cv::namedWindow(win, flags); }
void set_mouse_callback(const std::string &win, void (*cb)(int, int, int, int, void *), void *user)
{
    cv::setMouseCallback(win, cb, user);
}
double window_property(const std::string &win, int prop) { return cv::getWindowProperty(win, prop); }
void destroy_all_windows() { cv::destroyAllWindows(); }

const cylfe::media::Api kApi = {
    cylfe::media::kMediaAbi, imread, imwrite, imencode_png, video_open, video_read, video_get, video_close,
    writer_open, writer_write, writer_close, imshow, wait_key, named_window, set_mouse_callback, window_property,
    destroy_all_windows,
};

} // namespace

extern "C" __attribute__((visibility("default"))) const cylfe::media::Api *cyl_media_plugin(void) { return &kApi; }
