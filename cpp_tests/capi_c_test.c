/* Uses the C API from C (built -Wall -Wextra -Werror under ASan + UBSan): success paths with
 * checked values and every error path of the image functions, each verified to return its
 * specific status, set a message and leave the output buffer untouched. */
#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sketchbody.h"

_Static_assert(sizeof(skb_image) == 24, "skb_image layout is part of the ABI");
_Static_assert(sizeof(skb_status) == 4, "skb_status is uint32_t");

#include "c_check.h"

enum { W = 8, H = 6, SENTINEL = 0xAB };

static int untouched(const uint8_t *buf, size_t n) {
    for (size_t i = 0; i < n; ++i)
        if (buf[i] != SENTINEL) return 0;
    return 1;
}

/* Calls skb_image_canny expecting `want`, then checks message, text and untouched output. */
static void expect_canny(const char *what, const skb_image *src, double t1, double t2, int aperture, uint8_t *dst,
                         size_t stride, size_t len, skb_status want) {
    uint8_t buf[W * H * 4];
    memset(buf, SENTINEL, sizeof buf);
    uint8_t *out = dst ? buf : NULL;
    skb_status got = skb_image_canny(src, t1, t2, aperture, false, out, stride, len);
    if (got != want) {
        fprintf(stderr, "%s: status %u, expected %u (%s)\n", what, got, want, skb_last_error_message());
        ++failures;
        return;
    }
    CHECK(strlen(skb_last_error_message()) > 0);
    CHECK(strcmp(skb_status_str(got), "unknown status") != 0);
    CHECK(untouched(buf, sizeof buf));
    printf("error path ok: %-28s -> %u %s\n", what, got, skb_last_error_message());
}

int main(void) {
    /* Version: header macros agree with the runtime. */
    char expected[32];
    snprintf(expected, sizeof expected, "%d.%d.%d", SKB_VERSION_MAJOR, SKB_VERSION_MINOR, SKB_VERSION_PATCH);
    CHECK(strcmp(expected, SKB_VERSION_STRING) == 0);
    CHECK(strcmp(skb_version(), SKB_VERSION_STRING) == 0);

    /* A vertical step edge: columns 0-3 black, 4-7 white. OpenCV marks column 3 only. */
    uint8_t step[W * H];
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) step[y * W + x] = x < 4 ? 0 : 255;
    skb_image src = {step, W, H, W, 1};
    uint8_t edges[(W + 2) * H];
    memset(edges, SENTINEL, sizeof edges);
    CHECK(skb_image_canny(&src, 50, 150, 3, false, edges, W + 2, sizeof edges) == SKB_OK);
    CHECK(strcmp(skb_last_error_message(), "") == 0);
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) CHECK(edges[y * (W + 2) + x] == (x == 3 ? 255 : 0));
        if (y + 1 < H) CHECK(edges[y * (W + 2) + W] == SENTINEL && edges[y * (W + 2) + W + 1] == SENTINEL);
    }
    /* Thresholds in either order give the same map; a threshold above every gradient gives none. */
    uint8_t swapped[W * H], none[W * H];
    CHECK(skb_image_canny(&src, 150, 50, 3, false, swapped, W, sizeof swapped) == SKB_OK);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) CHECK(swapped[y * W + x] == edges[y * (W + 2) + x]);
    CHECK(skb_image_canny(&src, 5000, 6000, 3, true, none, W, sizeof none) == SKB_OK);
    for (int i = 0; i < W * H; ++i) CHECK(none[i] == 0);

    /* RGB input with a row stride wider than the row. */
    uint8_t rgb[H][W * 3 + 4];
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) memset(&rgb[y][x * 3], x < 4 ? 0 : 255, 3);
    skb_image rgb_src = {&rgb[0][0], W, H, W * 3 + 4, 3};
    uint8_t rgb_edges[W * H];
    CHECK(skb_image_canny(&rgb_src, 50, 150, 3, false, rgb_edges, W, sizeof rgb_edges) == SKB_OK);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) CHECK(rgb_edges[y * W + x] == edges[y * (W + 2) + x]);

    /* Every error path. */
    uint8_t dummy = 0;
    skb_image bad;
    expect_canny("NULL image", NULL, 50, 150, 3, &dummy, W, W * H, SKB_ERR_NULL_POINTER);
    bad = src; bad.data = NULL;
    expect_canny("NULL image data", &bad, 50, 150, 3, &dummy, W, W * H, SKB_ERR_NULL_POINTER);
    expect_canny("NULL output", &src, 50, 150, 3, NULL, W, W * H, SKB_ERR_NULL_POINTER);
    bad = src; bad.width = 0;
    expect_canny("zero width", &bad, 50, 150, 3, &dummy, W, W * H, SKB_ERR_EMPTY_IMAGE);
    bad = src; bad.height = 0;
    expect_canny("zero height", &bad, 50, 150, 3, &dummy, W, W * H, SKB_ERR_EMPTY_IMAGE);
    bad = src; bad.stride = W - 1;
    expect_canny("input stride < row", &bad, 50, 150, 3, &dummy, W, W * H, SKB_ERR_BAD_STRIDE);
    bad = src; bad.width = 16385; bad.stride = 16385;
    expect_canny("width > 16384", &bad, 50, 150, 3, &dummy, W, W * H, SKB_ERR_IMAGE_TOO_LARGE);
    bad = src; bad.channels = 2;
    expect_canny("2 channels", &bad, 50, 150, 3, &dummy, W, W * H, SKB_ERR_UNSUPPORTED_CHANNELS);
    expect_canny("aperture 4", &src, 50, 150, 4, &dummy, W, W * H, SKB_ERR_INVALID_APERTURE);
    expect_canny("aperture 1", &src, 50, 150, 1, &dummy, W, W * H, SKB_ERR_INVALID_APERTURE);
    expect_canny("NaN threshold", &src, NAN, 150, 3, &dummy, W, W * H, SKB_ERR_NON_FINITE);
    expect_canny("infinite threshold", &src, 50, INFINITY, 3, &dummy, W, W * H, SKB_ERR_NON_FINITE);
    expect_canny("output stride < width", &src, 50, 150, 3, &dummy, W - 1, W * H, SKB_ERR_BAD_STRIDE);
    expect_canny("output too small", &src, 50, 150, 3, &dummy, W, W * H - 1, SKB_ERR_BUFFER_TOO_SMALL);

    /* Blur: success on a constant image, then its own error paths. */
    uint8_t flat[W * H], blurred[W * H];
    memset(flat, 90, sizeof flat);
    skb_image flat_src = {flat, W, H, W, 1};
    CHECK(skb_image_gaussian_blur(&flat_src, 1.5, blurred, W, sizeof blurred) == SKB_OK);
    for (int i = 0; i < W * H; ++i) CHECK(blurred[i] == 90);
    memset(blurred, SENTINEL, sizeof blurred);
    CHECK(skb_image_gaussian_blur(&flat_src, 0.0, blurred, W, sizeof blurred) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_image_gaussian_blur(&flat_src, NAN, blurred, W, sizeof blurred) == SKB_ERR_NON_FINITE);
    CHECK(skb_image_gaussian_blur(&rgb_src, 1.0, blurred, W, sizeof blurred) == SKB_ERR_UNSUPPORTED_CHANNELS);
    CHECK(skb_image_gaussian_blur(&flat_src, 1.0, blurred, W, 3) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_image_gaussian_blur(&flat_src, 1.0, NULL, W, sizeof blurred) == SKB_ERR_NULL_POINTER);
    CHECK(untouched(blurred, sizeof blurred));

    /* Status texts: known codes have their own text, unknown ones say so. */
    CHECK(strcmp(skb_status_str(SKB_OK), "ok") == 0);
    CHECK(strcmp(skb_status_str(9999), "unknown status") == 0);

    printf("%s (%d failed checks)\n", failures ? "FAIL" : "PASS", failures);
    return failures ? 1 : 0;
}
