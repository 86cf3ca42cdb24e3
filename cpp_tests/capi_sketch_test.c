/* skb_context_render_sketch from C (built -Wall -Wextra -Werror under ASan + UBSan): a rendered sketch
 * lands in a strided buffer without touching the row padding, the same seed gives the same
 * bytes (also from two threads at once), another seed gives another sketch, the joints lie in
 * the image, and every error path returns its specific status, sets a message and leaves the
 * output untouched. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sketchbody.h"

#include "c_check.h"

enum { W = 120, H = 160, STRIDE = 128, LEN = STRIDE * H, SENTINEL = 0xAB };

static const skb_context *g_ctx;
static const skb_sketch_options *g_opts;

/* Renders the seed-`seed` clean sketch of a female body into `px` (LEN bytes). */
static skb_status render(uint64_t seed, uint8_t *px, double *joints, uint8_t *visible) {
    return skb_context_render_sketch(g_ctx, SKB_GENDER_FEMALE, NULL, 0, NULL, seed, W, H, g_opts, px, STRIDE, LEN, joints,
                             visible);
}

static void *render_thread(void *arg) {
    uint8_t *px = arg;
    skb_status st = render(11, px, NULL, NULL);
    return st == SKB_OK ? px : NULL;
}

static int all_equal(const uint8_t *buf, size_t n, uint8_t v) {
    for (size_t i = 0; i < n; ++i)
        if (buf[i] != v) return 0;
    return 1;
}

/* Calls skb_context_render_sketch with the given arguments expecting `want`; checks message and that
 * neither the pixels nor the joints were written. */
static void expect_error(const char *what, const skb_context *ctx, uint32_t gender, const float *weights,
                         size_t n_weights, const double *joints3d, uint32_t w, uint32_t h, size_t stride, size_t len,
                         skb_status want) {
    uint8_t *px = malloc(LEN);
    double j2[30];
    memset(px, SENTINEL, LEN);
    memset(j2, SENTINEL, sizeof j2);
    skb_status got = skb_context_render_sketch(ctx, gender, weights, n_weights, joints3d, 3, w, h, g_opts, px, stride, len,
                                       j2, NULL);
    if (got != want) {
        fprintf(stderr, "%s: status %u, expected %u (%s)\n", what, got, want, skb_last_error_message());
        ++failures;
    } else {
        CHECK(strlen(skb_last_error_message()) > 0);
        CHECK(all_equal(px, LEN, SENTINEL));
        CHECK(all_equal((const uint8_t *)j2, sizeof j2, SENTINEL));
        printf("error path ok: %-26s -> %u %s\n", what, got, skb_last_error_message());
    }
    free(px);
}

int main(void) {
    skb_context *ctx = NULL;
    CHECK(skb_context_new(&ctx) == SKB_OK);
    skb_sketch_options *opts = NULL;
    CHECK(skb_sketch_options_new(&opts) == SKB_OK);
    CHECK(skb_sketch_options_set_style(opts, SKB_SKETCH_STYLE_CLEAN) == SKB_OK);
    CHECK(skb_sketch_options_set_camera(opts, 5.0, 0.0, 0.0) == SKB_OK);
    CHECK(skb_sketch_options_set_style(opts, 9) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_sketch_options_set_camera(opts, 0.0, NAN, 0.0) == SKB_ERR_NON_FINITE);
    CHECK(skb_sketch_options_set_camera(NULL, 0.0, 0.0, 0.0) == SKB_ERR_NULL_POINTER);
    g_ctx = ctx;
    g_opts = opts;

    uint8_t *a = malloc(LEN), *b = malloc(LEN), *c = malloc(LEN);
    memset(a, SENTINEL, LEN);
    memset(b, SENTINEL, LEN);
    memset(c, SENTINEL, LEN);
    double joints[30];
    uint8_t visible[15];
    CHECK(render(11, a, joints, visible) == SKB_OK);
    size_t ink = 0;
    int padding_ok = 1;
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) ink += a[y * STRIDE + x] < 128;
        padding_ok &= all_equal(a + y * STRIDE + W, STRIDE - W, SENTINEL);
    }
    CHECK(padding_ok);
    CHECK(ink > 100 && ink < (size_t)(W * H) / 2);
    int n_visible = 0;
    for (int k = 0; k < 15; ++k) {
        CHECK(joints[2 * k] > 0 && joints[2 * k] < W && joints[2 * k + 1] > 0 && joints[2 * k + 1] < H);
        CHECK(visible[k] <= 1);
        n_visible += visible[k];
    }
    CHECK(n_visible >= 8);
    printf("sketch %dx%d seed 11: %zu ink pixels, %d of 15 joints visible, head (%.1f, %.1f)\n", W, H, ink, n_visible,
           joints[0], joints[1]);

    /* Two threads render the same seed at once: both equal the serial result. */
    pthread_t t1, t2;
    CHECK(pthread_create(&t1, NULL, render_thread, b) == 0);
    CHECK(pthread_create(&t2, NULL, render_thread, c) == 0);
    void *r1 = NULL, *r2 = NULL;
    pthread_join(t1, &r1);
    pthread_join(t2, &r2);
    CHECK(r1 == b && r2 == c);
    CHECK(memcmp(a, b, LEN) == 0 && memcmp(a, c, LEN) == 0);
    CHECK(render(12, b, NULL, NULL) == SKB_OK);
    uint8_t *tight = malloc((H - 1) * STRIDE + W);
    CHECK(skb_context_render_sketch(ctx, SKB_GENDER_FEMALE, NULL, 0, NULL, 11, W, H, opts, tight, STRIDE, (H - 1) * STRIDE + W,
                            NULL, NULL) == SKB_OK);
    int rows_equal = 1;
    for (int y = 0; y < H; ++y) rows_equal &= memcmp(tight + y * STRIDE, a + y * STRIDE, W) == 0;
    CHECK(rows_equal);
    free(tight);
    CHECK(memcmp(a, b, LEN) != 0);
    printf("determinism ok: same seed identical (serial and 2 threads), seed 12 differs\n");

    /* Given shape weights and 3-D joints (a T-pose-like stance): accepted. */
    float weights[4] = {1.0f, -0.5f, 0.25f, 0.0f};
    /* Canonical order: head, neck, r_shoulder, r_elbow, r_wrist, l_shoulder, l_elbow, l_wrist,
     * pelvis, r_hip, r_knee, r_ankle, l_hip, l_knee, l_ankle; facing +Z, so the right side is -X. */
    static const double tpose[45] = {0,    1.65, 0, 0,    1.5,  0, -0.2, 1.45, 0, -0.45, 1.45, 0, -0.7, 1.45, 0,
                                     0.2,  1.45, 0, 0.45, 1.45, 0, 0.7,  1.45, 0, 0,     1.0,  0, -0.1, 0.95, 0,
                                     -0.1, 0.5,  0, -0.1, 0.05, 0, 0.1,  0.95, 0, 0.1,   0.5,  0, 0.1,  0.05, 0};
    CHECK(skb_context_render_sketch(ctx, SKB_GENDER_MALE, weights, 4, tpose, 4, W, H, opts, c, STRIDE, LEN, NULL, NULL) ==
          SKB_OK);

    double nan_joints[45];
    for (int k = 0; k < 45; ++k) nan_joints[k] = tpose[k];
    nan_joints[7] = NAN;
    double zero_bone[45];
    for (int k = 0; k < 45; ++k) zero_bone[k] = tpose[k];
    for (int k = 0; k < 3; ++k) zero_bone[3 * 3 + k] = zero_bone[3 * 2 + k]; /* r_elbow on r_shoulder */
    float nan_weights[2] = {0.0f, NAN};
    float many[64] = {0};

    expect_error("NULL context", NULL, 0, NULL, 0, NULL, W, H, STRIDE, LEN, SKB_ERR_NULL_POINTER);
    expect_error("unknown gender", ctx, 2, NULL, 0, NULL, W, H, STRIDE, LEN, SKB_ERR_OUT_OF_RANGE);
    expect_error("zero width", ctx, 0, NULL, 0, NULL, 0, H, STRIDE, LEN, SKB_ERR_EMPTY_IMAGE);
    expect_error("width over 4096", ctx, 0, NULL, 0, NULL, 5000, H, STRIDE, LEN, SKB_ERR_OUT_OF_RANGE);
    expect_error("stride below width", ctx, 0, NULL, 0, NULL, W, H, W - 1, LEN, SKB_ERR_BAD_STRIDE);
    /* The last row needs no padding: (H - 1) * STRIDE + W bytes suffice, one fewer does not. */
    expect_error("buffer too small", ctx, 0, NULL, 0, NULL, W, H, STRIDE, (H - 1) * STRIDE + W - 1,
                 SKB_ERR_BUFFER_TOO_SMALL);
    expect_error("too many weights", ctx, 0, many, 64, NULL, W, H, STRIDE, LEN, SKB_ERR_OUT_OF_RANGE);
    expect_error("NaN weight", ctx, 0, nan_weights, 2, NULL, W, H, STRIDE, LEN, SKB_ERR_NON_FINITE);
    expect_error("NaN joint", ctx, 0, NULL, 0, nan_joints, W, H, STRIDE, LEN, SKB_ERR_NON_FINITE);
    expect_error("zero-length bone", ctx, 0, NULL, 0, zero_bone, W, H, STRIDE, LEN, SKB_ERR_DEGENERATE_BONE);

    free(a);
    free(b);
    free(c);
    skb_sketch_options_free(opts);
    skb_sketch_options_free(NULL);
    skb_context_free(ctx);
    if (failures) {
        fprintf(stderr, "capi_sketch_test: %d failures\n", failures);
        return 1;
    }
    printf("capi_sketch_test: PASS\n");
    return 0;
}
