// Uses the C API through sketchbody.hpp (built -Wall -Wextra -Werror under ASan + UBSan):
// RAII results, exceptions carrying status and message, and thread-local error messages that
// do not leak between threads.
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "sketchbody.hpp"

static_assert(sizeof(skb_image) == 24, "skb_image layout is part of the ABI");
static_assert(sizeof(skb_status) == 4, "skb_status is 32 bits");

static int failures = 0;
#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (!(cond)) {                                                                \
            std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
            ++failures;                                                               \
        }                                                                             \
    } while (0)

struct Dummy {};
static int frees = 0;
static void free_dummy(Dummy *d) {
    if (d) {
        ++frees;
        delete d;
    }
}

template <typename F>
static skb_status status_of(F &&f) {
    try {
        f();
    } catch (const sketchbody::Error &e) {
        CHECK(std::string(e.what()).size() > 0);
        return e.status();
    }
    return SKB_OK;
}

int main() {
    CHECK(sketchbody::version() == SKB_VERSION_STRING);

    // A white square on black: Canny outlines it; every edge pixel lies on the square's border.
    const uint32_t n = 32;
    sketchbody::GrayImage img{n, n, std::vector<uint8_t>(n * n, 0)};
    for (uint32_t y = 8; y < 24; ++y)
        for (uint32_t x = 8; x < 24; ++x) img.pixels[y * n + x] = 255;
    sketchbody::GrayImage edges = sketchbody::canny(img.view(), 50, 150);
    size_t count = 0;
    for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x)
            if (edges.pixels[y * n + x]) {
                ++count;
                CHECK((x >= 7 && x <= 8) || (x >= 23 && x <= 24) || (y >= 7 && y <= 8) || (y >= 23 && y <= 24));
            }
    CHECK(count >= 60);

    // Errors become exceptions with the specific status.
    skb_image bad = img.view();
    bad.channels = 5;
    CHECK(status_of([&] { sketchbody::canny(bad, 1, 2); }) == SKB_ERR_UNSUPPORTED_CHANNELS);
    CHECK(status_of([&] { sketchbody::canny(img.view(), 1, 2, 9); }) == SKB_ERR_INVALID_APERTURE);
    CHECK(status_of([&] { sketchbody::canny(img.view(), NAN, 2); }) == SKB_ERR_NON_FINITE);
    CHECK(status_of([&] { sketchbody::gaussian_blur(img.view(), -1.0); }) == SKB_ERR_OUT_OF_RANGE);

    // Thread-local messages: an error on one thread leaves another thread's success clean.
    std::string other_thread_message = "not run";
    std::thread t([&] {
        sketchbody::canny(img.view(), 10, 20);
        other_thread_message = skb_last_error_message();
    });
    CHECK(status_of([&] { sketchbody::canny(bad, 1, 2); }) == SKB_ERR_UNSUPPORTED_CHANNELS);
    t.join();
    CHECK(other_thread_message.empty());
    CHECK(std::string(skb_last_error_message()).find("channel") != std::string::npos);

    // Handle<T, Free> is move-only and frees once (exercised with a counting deleter).
    using H = sketchbody::Handle<Dummy, free_dummy>;
    {
        H a(new Dummy);
        H b(std::move(a));
        CHECK(!a && b);
        H c;
        c = std::move(b);
    }
    CHECK(frees == 1);

    std::printf("%s (%d failed checks)\n", failures ? "FAIL" : "PASS", failures);
    return failures ? 1 : 0;
}
