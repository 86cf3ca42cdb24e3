// Synthetic test images shared by the Canny comparison and benchmark programs.
#pragma once
#include <opencv2/imgproc.hpp>
#include <random>

namespace skbtest {

// A white page with `strokes` random dark strokes (lines, arcs, polylines; anti-aliased or not,
// 1-4 px wide), like a concept sketch's line art. Deterministic for a given seed.
inline cv::Mat line_drawing(int width, int height, int strokes, unsigned seed) {
    cv::Mat img(height, width, CV_8UC1, cv::Scalar(255));
    std::mt19937 rng(seed);
    auto uni = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    for (int s = 0; s < strokes; ++s) {
        const int kind = uni(0, 2);
        const int thick = uni(1, 4);
        const int tone = uni(0, 120);
        const int aa = uni(0, 1) ? cv::LINE_AA : cv::LINE_8;
        cv::Point a(uni(-10, width + 10), uni(-10, height + 10));
        if (kind == 0) {
            cv::Point b(uni(-10, width + 10), uni(-10, height + 10));
            cv::line(img, a, b, cv::Scalar(tone), thick, aa);
        } else if (kind == 1) {
            cv::Size axes(uni(1, std::max(2, width / 3)), uni(1, std::max(2, height / 3)));
            cv::ellipse(img, a, axes, uni(0, 180), uni(0, 180), uni(180, 360), cv::Scalar(tone), thick, aa);
        } else {
            std::vector<cv::Point> pts;
            for (int k = 0; k < 6; ++k) pts.emplace_back(uni(0, width), uni(0, height));
            cv::polylines(img, pts, false, cv::Scalar(tone), thick, aa);
        }
    }
    return img;
}

inline cv::Mat noise_image(int width, int height, unsigned seed) {
    cv::Mat img(height, width, CV_8UC1);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> d(0, 255);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) img.at<uchar>(y, x) = (uchar)d(rng);
    return img;
}

}  // namespace skbtest
