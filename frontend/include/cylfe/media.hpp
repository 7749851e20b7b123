// SPDX-License-Identifier: BSD-3-Clause
// Image files, video files and windows: OpenCV's imgcodecs, videoio and highgui, reached through
// the plugin libcyl-media.so, loaded at first use. A tool that never reads an image file, writes a
// video or opens a window (a camera or raw log in, observations out: the robot's case) then never
// loads those modules and the ~230 shared libraries behind them (codecs, GStreamer, FFmpeg, GDAL,
// Qt); `cyl` itself links OpenCV's core and imgproc only.
//
// The plugin is looked up, first hit wins, as
//   1. $CYL_MEDIA_PLUGIN, when set (and then only there);
//   2. <directory of the executable>/libcyl-media.so and ../libcyl-media.so (the build tree);
//   3. <directory of the executable>/../lib/cyl/libcyl-media.so (installed by make install).
// When it cannot be loaded, the call that needed it throws Error naming the places tried.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace cylfe {
namespace media {

// The plugin's interface (version kMediaAbi). Both sides are this project's C++17 build.
constexpr int kMediaAbi = 1;
struct Api {
    int abi;
    bool (*imread)(const std::string &path, int flags, cv::Mat &out);
    bool (*imwrite)(const std::string &path, const cv::Mat &img);
    bool (*imencode_png)(const cv::Mat &img, std::vector<uint8_t> &out);
    void *(*video_open)(const std::string &path);
    bool (*video_read)(void *video, cv::Mat &out);
    double (*video_get)(void *video, int prop);
    void (*video_close)(void *video);
    void *(*writer_open)(const std::string &path, int fourcc, double fps, cv::Size size);
    void (*writer_write)(void *writer, const cv::Mat &img);
    void (*writer_close)(void *writer);
    void (*imshow)(const std::string &window, const cv::Mat &img);
    int (*wait_key)(int ms);
    void (*named_window)(const std::string &window, int flags);
    void (*set_mouse_callback)(const std::string &window, void (*cb)(int, int, int, int, void *), void *user);
    double (*window_property)(const std::string &window, int prop);
    void (*destroy_all_windows)();
};

// The loaded plugin (loads it on the first call); throws Error when it cannot be loaded.
const Api &api();

// Where the plugin was found ("" before the first successful load).
std::string plugin_path();

// cv::imread / cv::imwrite / cv::imencode(".png") through the plugin (cv::IMREAD_* flags).
inline cv::Mat imread(const std::string &path, int flags)
{
    cv::Mat m;
    api().imread(path, flags, m);
    return m;
}
inline bool imwrite(const std::string &path, const cv::Mat &img) { return api().imwrite(path, img); }
inline bool imencode_png(const cv::Mat &img, std::vector<uint8_t> &out) { return api().imencode_png(img, out); }

// A video file read frame by frame (cv::VideoCapture).
class VideoReader {
public:
    VideoReader() = default;
    VideoReader(const VideoReader &) = delete;
    VideoReader &operator=(const VideoReader &) = delete;
    ~VideoReader() { close(); }
    bool open(const std::string &path) { close(); h_ = api().video_open(path); return h_ != nullptr; }
    bool read(cv::Mat &out) { return h_ && api().video_read(h_, out); }
    double get(int cap_prop) const { return h_ ? api().video_get(h_, cap_prop) : 0.0; }
    void close() { if (h_) api().video_close(h_); h_ = nullptr; }
private:
    void *h_ = nullptr;
};

// A video file written frame by frame (cv::VideoWriter).
class VideoWriter {
public:
    VideoWriter() = default;
    VideoWriter(const VideoWriter &) = delete;
    VideoWriter &operator=(const VideoWriter &) = delete;
    ~VideoWriter() { close(); }
    static int fourcc(char a, char b, char c, char d)
    {
        return (a & 255) | ((b & 255) << 8) | ((c & 255) << 16) | ((d & 255) << 24);
    }
    bool open(const std::string &path, int fourcc, double fps, cv::Size size)
    {
        close();
        h_ = api().writer_open(path, fourcc, fps, size);
        return h_ != nullptr;
    }
    bool is_open() const { return h_ != nullptr; }
    void write(const cv::Mat &img) { if (h_) api().writer_write(h_, img); }
    void close() { if (h_) api().writer_close(h_); h_ = nullptr; }
private:
    void *h_ = nullptr;
};

// Windows (cv::imshow, cv::waitKey, cv::namedWindow, cv::setMouseCallback, cv::getWindowProperty,
// cv::destroyAllWindows).
inline void imshow(const std::string &window, const cv::Mat &img) { api().imshow(window, img); }
inline int wait_key(int ms) { return api().wait_key(ms); }
inline void named_window(const std::string &window, int flags) { api().named_window(window, flags); }
inline void set_mouse_callback(const std::string &window, void (*cb)(int, int, int, int, void *), void *user)
{
    api().set_mouse_callback(window, cb, user);
}
inline double window_property(const std::string &window, int prop) { return api().window_property(window, prop); }
inline void destroy_all_windows() { api().destroy_all_windows(); }

} // namespace media
} // namespace cylfe
