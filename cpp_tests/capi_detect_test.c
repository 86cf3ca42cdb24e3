/* skb_detect from C (built -Wall -Wextra -Werror under ASan + UBSan): the context's embedded
 * detector finds the figure of a rendered sketch (strided buffer) close to its true joints, two
 * threads get the same answer, options set the threshold, the searched scales, the figure range
 * and the levels per octave, "no figure" returns SKB_ERR_NO_FIGURE with the best score (from
 * skb_detect and skb_detector_detect), and every error path returns its specific
 * status with a message and leaves the joints untouched. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sketchbody.h"

#include "c_check.h"

enum { W = 384, H = 384, STRIDE = 400, LEN = STRIDE * H };

static const skb_context *g_ctx;
static skb_image g_img;

struct result {
    double xy[30], conf[15], score;
    skb_status st;
};

static void *detect_thread(void *arg) {
    struct result *r = arg;
    r->st = skb_detect(g_ctx, &g_img, NULL, r->xy, 30, r->conf, 15, &r->score);
    return NULL;
}

/* Fraction of joints within alpha x the longer side of the true joints' box. */
static double pck(const double *truth, const double *est, double alpha) {
    double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
    for (int k = 0; k < 15; ++k)
        for (int a = 0; a < 2; ++a) {
            lo[a] = fmin(lo[a], truth[2 * k + a]);
            hi[a] = fmax(hi[a], truth[2 * k + a]);
        }
    double thr = alpha * fmax(hi[0] - lo[0], hi[1] - lo[1]);
    int hit = 0;
    for (int k = 0; k < 15; ++k) hit += hypot(truth[2 * k] - est[2 * k], truth[2 * k + 1] - est[2 * k + 1]) <= thr;
    return hit / 15.0;
}

int main(void) {
    skb_context *ctx = NULL;
    CHECK(skb_context_new(&ctx) == SKB_OK);
    skb_sketch_options *so = NULL;
    CHECK(skb_sketch_options_new(&so) == SKB_OK);
    CHECK(skb_sketch_options_set_style(so, SKB_SKETCH_STYLE_CLEAN) == SKB_OK);
    uint8_t *px = malloc(LEN);
    memset(px, 255, LEN);
    double truth[30];
    CHECK(skb_render_sketch(ctx, SKB_GENDER_MALE, NULL, 0, NULL, 21, W, H, so, px, STRIDE, LEN, truth, NULL) == SKB_OK);
    g_ctx = ctx;
    g_img = (skb_image){px, W, H, STRIDE, 1};

    struct result a, b, c;
    pthread_t t1, t2;
    detect_thread(&a);
    CHECK(a.st == SKB_OK);
    CHECK(pthread_create(&t1, NULL, detect_thread, &b) == 0);
    CHECK(pthread_create(&t2, NULL, detect_thread, &c) == 0);
    pthread_join(t1, NULL);
    pthread_join(t2, NULL);
    CHECK(b.st == SKB_OK && c.st == SKB_OK);
    CHECK(memcmp(a.xy, b.xy, sizeof a.xy) == 0 && memcmp(a.xy, c.xy, sizeof a.xy) == 0 && a.score == b.score);
    double p1 = pck(truth, a.xy, 0.1), p2 = pck(truth, a.xy, 0.2);
    CHECK(p2 >= 0.8);
    int conf_ok = 1;
    for (int k = 0; k < 15; ++k) conf_ok &= a.conf[k] > 0.0 && a.conf[k] < 1.0;
    CHECK(conf_ok && isfinite(a.score));
    printf("sketch %dx%d seed 21: score %.3f, PCK@0.1 %.2f, PCK@0.2 %.2f, head (%.1f, %.1f) vs true (%.1f, %.1f); "
           "2 threads identical\n",
           W, H, a.score, p1, p2, a.xy[0], a.xy[1], truth[0], truth[1]);

    skb_detect_options *o = NULL;
    CHECK(skb_detect_options_new(&o) == SKB_OK);
    /* A threshold above the best score: no figure, the score is still reported. */
    CHECK(skb_detect_options_set_threshold(o, a.score + 1.0) == SKB_OK);
    double xy[30], conf[15], score = 0.0;
    memset(xy, 0xAB, sizeof xy);
    double sentinel = xy[0];
    CHECK(skb_detect(ctx, &g_img, o, xy, 30, conf, 15, &score) == SKB_ERR_NO_FIGURE);
    CHECK(fabs(score - a.score) < 1e-9);
    CHECK(strstr(skb_last_error_message(), "no figure") != NULL);
    CHECK(memcmp(&xy[0], &sentinel, sizeof sentinel) == 0);
    printf("no figure ok: %s\n", skb_last_error_message());
    /* The same no-figure report from a detector loaded by the caller: the embedded model's file. */
    skb_detector *det = NULL;
    CHECK(skb_detector_new_from_file(SKB_SOURCE_DIR "/assets/detector.skbd", &det) == SKB_OK);
    double score2 = 0.0;
    memset(xy, 0xAB, sizeof xy);
    CHECK(skb_detector_detect(det, &g_img, a.score + 1.0, 0.0, xy, 30, conf, 15, &score2) == SKB_ERR_NO_FIGURE);
    CHECK(fabs(score2 - a.score) < 1e-9);
    CHECK(memcmp(&xy[0], &sentinel, sizeof sentinel) == 0);
    CHECK(skb_detector_detect(det, &g_img, NAN, 0.0, xy, 30, conf, 15, &score2) == SKB_OK);
    CHECK(fabs(score2 - a.score) < 1e-9);
    skb_detector_free(det);
    skb_detector_free(NULL);
    printf("no figure from skb_detector_detect ok: score %.3f\n", a.score);
    /* Ten levels per octave (the model's own) search a superset of the levels of five. */
    CHECK(skb_detect_options_set_threshold(o, -1e9) == SKB_OK);
    CHECK(skb_detect_options_set_levels_per_octave(o, 5) == SKB_OK);
    double score5 = 0.0;
    CHECK(skb_detect(ctx, &g_img, o, xy, 30, conf, 15, &score5) == SKB_OK);
    CHECK(skb_detect_options_set_levels_per_octave(o, 0) == SKB_OK);
    CHECK(skb_detect(ctx, &g_img, o, xy, 30, conf, 15, &score) == SKB_OK);
    CHECK(score >= score5 && pck(truth, xy, 0.2) >= 0.8);
    printf("levels per octave: best score %.3f with 5, %.3f with 10, %.3f with the default 7\n", score5, score, a.score);
    CHECK(skb_detect_options_set_levels_per_octave(o, 101) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_levels_per_octave(NULL, 5) == SKB_ERR_NULL_POINTER);
    CHECK(skb_detect_options_set_levels_per_octave(o, 7) == SKB_OK);
    /* Only figures of at most 0.3 of the side: the page-filling figure scores lower. */
    CHECK(skb_detect_options_set_figure_range(o, 0.05, 0.3) == SKB_OK);
    CHECK(skb_detect(ctx, &g_img, o, xy, 30, conf, 15, &score) == SKB_OK);
    CHECK(score < a.score);
    CHECK(skb_detect_options_set_figure_range(o, 0.5, 0.5) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_figure_range(o, 0.0, 1.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_figure_range(o, NAN, 1.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_threshold(o, NAN) == SKB_OK);
    CHECK(skb_detect_options_set_threshold(o, INFINITY) == SKB_ERR_NON_FINITE);
    CHECK(skb_detect_options_set_threshold(NULL, 0.0) == SKB_ERR_NULL_POINTER);
    /* Scales of the figure only (its cells are about height / 40 px): same answer, less work. */
    CHECK(skb_detect_options_set_scales(o, 4.0, 16.0) == SKB_OK);
    CHECK(skb_detect(ctx, &g_img, o, xy, 30, conf, 15, &score) == SKB_OK);
    CHECK(pck(truth, xy, 0.2) >= 0.8);
    CHECK(skb_detect_options_set_scales(o, 8.0, 8.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_scales(o, -1.0, 8.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_scales(o, NAN, 8.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(strlen(skb_last_error_message()) > 0);

    /* Error paths: nothing written. */
    memset(xy, 0xAB, sizeof xy);
    CHECK(skb_detect(NULL, &g_img, o, xy, 30, conf, 15, &score) == SKB_ERR_NULL_POINTER);
    CHECK(skb_detect(ctx, NULL, o, xy, 30, conf, 15, &score) == SKB_ERR_NULL_POINTER);
    CHECK(skb_detect(ctx, &g_img, o, xy, 29, conf, 15, &score) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_detect(ctx, &g_img, o, xy, 30, conf, 14, &score) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_detect(ctx, &g_img, o, xy, 30, conf, 15, NULL) == SKB_ERR_NULL_POINTER);
    skb_image tiny = {px, 20, 20, STRIDE, 1};
    CHECK(skb_detect(ctx, &tiny, o, xy, 30, conf, 15, &score) == SKB_ERR_IMAGE_TOO_SMALL);
    skb_image bad_stride = {px, W, H, W - 1, 1};
    CHECK(skb_detect(ctx, &bad_stride, o, xy, 30, conf, 15, &score) == SKB_ERR_BAD_STRIDE);
    CHECK(memcmp(&xy[0], &sentinel, sizeof sentinel) == 0);
    printf("error paths ok: %s\n", skb_last_error_message());

    skb_detect_options_free(o);
    skb_detect_options_free(NULL);
    skb_sketch_options_free(so);
    skb_context_free(ctx);
    free(px);
    if (failures) {
        fprintf(stderr, "capi_detect_test: %d failures\n", failures);
        return 1;
    }
    printf("capi_detect_test: PASS\n");
    return 0;
}
