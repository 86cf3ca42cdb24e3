// Benchmark (not a test): times cv::Canny and skb_image_canny on the same line drawings in one
// process, interleaved (OpenCV, ours, OpenCV, ours, ...), and prints the median of per-pair
// time ratios ours/OpenCV. Usage: canny_bench [--threads N] [--reps R]
// --threads 1 pins both libraries to one thread (cv::setNumThreads, RAYON_NUM_THREADS);
// --threads 0 (default) lets both use every core.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "sketchbody.h"
#include "test_images.hpp"

static double now_ms() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

static double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int main(int argc, char **argv) {
    int threads = 0, reps = 15;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
    }
    if (threads > 0) {
        setenv("RAYON_NUM_THREADS", std::to_string(threads).c_str(), 1);  // before the first library call
        cv::setNumThreads(threads);
    }
    std::printf("canny benchmark: sketchbody %s vs OpenCV %s, threads %s (OpenCV uses %d), %d interleaved pairs\n",
                skb_version(), CV_VERSION, threads > 0 ? std::to_string(threads).c_str() : "all", cv::getNumThreads(), reps);
    std::printf("| size | drawing | gradient | OpenCV ms | sketchbody ms | ours/OpenCV (median of pairs) |\n");
    std::printf("|---|---|---|---|---|---|\n");
    for (int size : {512, 1024, 2048})
        for (int dense : {0, 1}) {
            int strokes = dense ? size * size / 1500 : size * size / 40000;
            cv::Mat img = skbtest::line_drawing(size, size, strokes, 1000u + size + dense);
            for (bool l2 : {false, true}) {
                std::vector<uint8_t> dst((size_t)size * size);
                skb_image src{img.data, (uint32_t)size, (uint32_t)size, (uint32_t)img.step[0], 1};
                cv::Mat ref;
                std::vector<double> t_cv, t_ours, ratio;
                for (int r = -2; r < reps; ++r) {  // two warm-up pairs
                    double a = now_ms();
                    cv::Canny(img, ref, 50, 150, 3, l2);
                    double b = now_ms();
                    if (skb_image_canny(&src, 50, 150, 3, l2, dst.data(), (size_t)size, dst.size()) != SKB_OK) {
                        std::printf("skb_image_canny failed: %s\n", skb_last_error_message());
                        return 1;
                    }
                    double c = now_ms();
                    if (r < 0) continue;
                    t_cv.push_back(b - a);
                    t_ours.push_back(c - b);
                    ratio.push_back((c - b) / (b - a));
                }
                if (std::memcmp(ref.data, dst.data(), dst.size()) != 0) {
                    std::printf("edge maps differ\n");
                    return 1;
                }
                std::printf("| %d² | %s | %s | %.2f | %.2f | %.2f |\n", size, dense ? "dense" : "sparse", l2 ? "L2" : "L1",
                            median(t_cv), median(t_ours), median(ratio));
            }
        }
    return 0;
}
