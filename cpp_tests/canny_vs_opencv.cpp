// Compares sketchbody's Canny (through the C API) with OpenCV's cv::Canny on whole edge maps:
// synthetic line drawings of several densities and sizes (including 1x1, 1xN, Nx1), constant and
// noise images and the PARSE photos, x apertures {3,5,7} x {L1,L2} x threshold pairs (including
// low > high and thresholds above every gradient). Also colour input (RGB, RGBA, strided) against
// cvtColor + Canny, and the Gaussian blur against cv::GaussianBlur. Passes only when no pixel
// differs. Usage: canny_vs_opencv [PARSE_IMAGE_DIR]
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "sketchbody.h"
#include "test_images.hpp"

namespace {

struct Totals {
    long combos = 0;
    long pixels = 0;
    long differing = 0;
    long failed_calls = 0;
};

struct Thresholds {
    double t1, t2;
};

// Runs both implementations on `img` (gray, or colour in RGB/RGBA order for ours) and counts
// differing pixels. `gray` is what OpenCV sees.
long compare_one(const cv::Mat &ours_input, const cv::Mat &gray, Thresholds th, int aperture, bool l2,
                 const std::string &name, Totals &t) {
    cv::Mat ref;
    cv::Canny(gray, ref, th.t1, th.t2, aperture, l2);
    const size_t w = (size_t)gray.cols, h = (size_t)gray.rows;
    const size_t dst_stride = w + 3;  // a stride wider than the row, to exercise it
    std::vector<uint8_t> dst(dst_stride * h, 77);
    skb_image src{ours_input.data, (uint32_t)ours_input.cols, (uint32_t)ours_input.rows, (uint32_t)ours_input.step[0],
                  (uint32_t)ours_input.channels()};
    skb_status st = skb_image_canny(&src, th.t1, th.t2, aperture, l2, dst.data(), dst_stride, dst.size());
    ++t.combos;
    if (st != SKB_OK) {
        std::printf("FAIL %s: skb_image_canny returned %u: %s\n", name.c_str(), st, skb_last_error_message());
        ++t.failed_calls;
        return 1;
    }
    long diff = 0;
    for (size_t y = 0; y < h; ++y) {
        for (size_t x = 0; x < w; ++x) diff += dst[y * dst_stride + x] != ref.at<uchar>((int)y, (int)x);
        for (size_t x = w; x < dst_stride && y + 1 < h; ++x) diff += dst[y * dst_stride + x] != 77;  // padding untouched
    }
    t.pixels += (long)(w * h);
    t.differing += diff;
    if (diff) {
        std::printf("DIFF %s t1=%g t2=%g aperture=%d %s: %ld pixels\n", name.c_str(), th.t1, th.t2, aperture,
                    l2 ? "L2" : "L1", diff);
    }
    return diff;
}

void compare_all_settings(const cv::Mat &ours_input, const cv::Mat &gray, const std::string &name, Totals &t) {
    const Thresholds pairs[] = {{20, 60}, {100, 300}, {300, 100}, {1000, 4000}, {1e6, 2e6}, {-10, 5}};
    for (int aperture : {3, 5, 7})
        for (bool l2 : {false, true})
            for (const Thresholds &th : pairs) compare_one(ours_input, gray, th, aperture, l2, name, t);
}

long compare_blur(const cv::Mat &gray, double sigma, const std::string &name, int &max_abs) {
    cv::Mat ref;
    cv::GaussianBlur(gray, ref, cv::Size(0, 0), sigma);
    const size_t w = (size_t)gray.cols, h = (size_t)gray.rows;
    std::vector<uint8_t> dst(w * h);
    skb_image src{gray.data, (uint32_t)w, (uint32_t)h, (uint32_t)gray.step[0], 1};
    if (skb_image_gaussian_blur(&src, sigma, dst.data(), w, dst.size()) != SKB_OK) {
        std::printf("FAIL blur %s: %s\n", name.c_str(), skb_last_error_message());
        return (long)(w * h);
    }
    long diff = 0;
    for (size_t y = 0; y < h; ++y)
        for (size_t x = 0; x < w; ++x) {
            int d = std::abs((int)dst[y * w + x] - (int)ref.at<uchar>((int)y, (int)x));
            diff += d != 0;
            max_abs = std::max(max_abs, d);
        }
    if (diff) std::printf("BLUR DIFF %s sigma=%g: %ld pixels\n", name.c_str(), sigma, diff);
    return diff;
}

}  // namespace

int main(int argc, char **argv) {
    std::printf("sketchbody %s vs OpenCV %s\n", skb_version(), CV_VERSION);
    Totals t;
    std::vector<std::pair<std::string, cv::Mat>> grays;
    // Synthetic line drawings: sizes (odd, degenerate) x densities.
    const int sizes[][2] = {{1, 1}, {1, 37}, {41, 1}, {2, 2}, {3, 5}, {7, 4}, {97, 131}, {256, 256}, {333, 257}, {640, 480}};
    unsigned seed = 1;
    for (auto &s : sizes)
        for (int density : {1, 8, 40}) {
            int strokes = std::max(1, density * s[0] * s[1] / 10000 + density / 4);
            grays.emplace_back("lines_" + std::to_string(s[0]) + "x" + std::to_string(s[1]) + "_d" + std::to_string(density),
                               skbtest::line_drawing(s[0], s[1], strokes, seed++));
        }
    for (int v : {0, 128, 255}) grays.emplace_back("const" + std::to_string(v), cv::Mat(13, 17, CV_8UC1, cv::Scalar(v)));
    grays.emplace_back("noise_100x80", skbtest::noise_image(100, 80, 7));
    grays.emplace_back("noise_255x255", skbtest::noise_image(255, 255, 8));
    grays.emplace_back("noise_1x9", skbtest::noise_image(1, 9, 9));
    for (auto &g : grays) compare_all_settings(g.second, g.second, g.first, t);
    const long synthetic = t.combos;

    // PARSE photos: gray (as OpenCV reads them) and colour through our RGB conversion.
    int photos = 0;
    if (argc > 1) {
        std::vector<cv::String> files;
        try {
            cv::glob(std::string(argv[1]) + "/*.jpg", files);
        } catch (const cv::Exception &) {
            files.clear();  // a missing directory is reported below
        }
        for (size_t i = 0; i < files.size(); ++i) {
            cv::Mat bgr = cv::imread(files[i], cv::IMREAD_COLOR);
            if (bgr.empty()) continue;
            ++photos;
            cv::Mat gray, rgb;
            cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
            std::string name = files[i].substr(files[i].find_last_of('/') + 1);
            if (i % 4 == 0) {
                compare_all_settings(gray, gray, name, t);
            } else {
                // Colour input (RGB, RGBA, or RGB inside a wider buffer) against cvtColor + Canny.
                cv::cvtColor(bgr, rgb, i % 4 == 1 ? cv::COLOR_BGR2RGB : cv::COLOR_BGR2RGBA);
                if (i % 4 == 3) {
                    cv::Mat wide(rgb.rows, rgb.cols + 5, rgb.type(), cv::Scalar::all(0));
                    rgb.copyTo(wide(cv::Rect(0, 0, rgb.cols, rgb.rows)));
                    rgb = wide(cv::Rect(0, 0, rgb.cols, rgb.rows));
                }
                compare_all_settings(rgb, gray, name + (i % 4 == 1 ? "_rgb" : i % 4 == 2 ? "_rgba" : "_rgba_strided"), t);
            }
        }
    }
    if (photos == 0) {
        const bool required = std::getenv("SKB_REQUIRE_SHARED_DATA") != nullptr;
        std::printf("%s PARSE photos: none found%s\n", required ? "FAIL" : "SKIPPED",
                    required ? " but SKB_REQUIRE_SHARED_DATA is set" : "");
        if (required) return 1;
    }

    // Gaussian blur compatibility.
    long blur_diff = 0, blur_runs = 0;
    int blur_max = 0;
    for (size_t i = 0; i < grays.size(); i += 2)
        for (double sigma : {0.5, 1.0, 1.4, 2.0, 3.3}) {
            blur_diff += compare_blur(grays[i].second, sigma, grays[i].first, blur_max);
            ++blur_runs;
        }

    std::printf("canny: %ld combinations (%ld synthetic, %ld on %d PARSE photos), %ld pixels compared, "
                "%ld differing pixels, %ld failed calls\n",
                t.combos, synthetic, t.combos - synthetic, photos, t.pixels, t.differing, t.failed_calls);
    std::printf("gaussian blur: %ld runs, %ld differing pixels, max |difference| %d\n", blur_runs, blur_diff, blur_max);
    const bool ok = t.differing == 0 && t.failed_calls == 0 && t.combos >= 300 && blur_diff == 0;
    std::printf("%s\n", ok ? "PASS" : "FAIL");
    return ok ? 0 : 1;
}
