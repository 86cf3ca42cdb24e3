// sketchbody.hpp: header-only C++17 RAII wrapper over the sketchbody C API (sketchbody.h).
// Errors become sketchbody::Error exceptions carrying the status and the library's message.
// Handles are move-only and free themselves. Thread-safety is that of the wrapped C objects.
#ifndef SKETCHBODY_HPP
#define SKETCHBODY_HPP

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sketchbody.h"

namespace sketchbody {

/// A failed sketchbody call: status() is the skb_status code, what() the specific message.
class Error : public std::runtime_error {
public:
    Error(skb_status status, const std::string &message) : std::runtime_error(message), status_(status) {}
    skb_status status() const noexcept { return status_; }

private:
    skb_status status_;
};

/// Throws Error for any status other than SKB_OK.
inline void check(skb_status status) {
    if (status != SKB_OK) {
        std::string message = skb_last_error_message();
        if (message.empty()) message = skb_status_str(status);
        throw Error(status, message);
    }
}

/// Version of the loaded library ("MAJOR.MINOR.PATCH"); compare with SKB_VERSION_STRING.
inline std::string version() { return skb_version(); }

/// Owns a C handle T* released with Free (NULL-safe). Move-only.
template <typename T, void (*Free)(T *)>
class Handle {
public:
    Handle() = default;
    explicit Handle(T *raw) noexcept : raw_(raw) {}
    Handle(const Handle &) = delete;
    Handle &operator=(const Handle &) = delete;
    Handle(Handle &&other) noexcept : raw_(std::exchange(other.raw_, nullptr)) {}
    Handle &operator=(Handle &&other) noexcept {
        if (this != &other) {
            Free(raw_);
            raw_ = std::exchange(other.raw_, nullptr);
        }
        return *this;
    }
    ~Handle() { Free(raw_); }
    T *get() const noexcept { return raw_; }
    T **out() noexcept {  // for C functions that create into T** (frees any current value)
        Free(raw_);
        raw_ = nullptr;
        return &raw_;
    }
    explicit operator bool() const noexcept { return raw_ != nullptr; }

private:
    T *raw_ = nullptr;
};

/// An owned, tightly packed 8-bit gray image.
struct GrayImage {
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<uint8_t> pixels;  // width * height bytes, row-major

    /// A borrowed skb_image view of this image (valid while the image lives).
    skb_image view() const noexcept { return skb_image{pixels.data(), width, height, width, 1}; }
};

/// Canny edges (255 edge / 0), bit-exact with OpenCV's cv::Canny; see skb_canny.
inline GrayImage canny(const skb_image &src, double threshold1, double threshold2, int aperture = 3,
                       bool l2_gradient = false) {
    GrayImage out{src.width, src.height, std::vector<uint8_t>(size_t(src.width) * src.height)};
    check(skb_canny(&src, threshold1, threshold2, aperture, l2_gradient, out.pixels.data(), src.width,
                    out.pixels.size()));
    return out;
}

/// Gaussian blur of a gray image, compatible with cv::GaussianBlur(Size(0,0), sigma).
inline GrayImage gaussian_blur(const skb_image &src, double sigma) {
    GrayImage out{src.width, src.height, std::vector<uint8_t>(size_t(src.width) * src.height)};
    check(skb_gaussian_blur(&src, sigma, out.pixels.data(), src.width, out.pixels.size()));
    return out;
}

}  // namespace sketchbody

#endif  // SKETCHBODY_HPP
