/* skb_context_detect from C (built -Wall -Wextra -Werror under ASan + UBSan): the context's embedded
 * backends find the figure of a rendered sketch (strided buffer) close to its true joints with
 * calibrated confidences, two threads get the same answer, skb_context_detect_figure reports the backend
 * kept and the low-confidence flag, options choose the backend, strictness, the threshold, the
 * searched scales, the figure range and the levels per octave, "no figure" returns
 * SKB_ERR_NO_FIGURE (a blank page; strict with an unreachable threshold, with the best raw score
 * from skb_context_detect and skb_detector_detect), and every error path returns its specific status
 * with a message and leaves the joints untouched. */
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
    r->st = skb_context_detect(g_ctx, &g_img, NULL, r->xy, 30, r->conf, 15, &r->score);
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
    CHECK(skb_context_render_sketch(ctx, SKB_GENDER_MALE, NULL, 0, NULL, 21, W, H, so, px, STRIDE, LEN, truth, NULL) == SKB_OK);
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
    double mean_conf = 0.0;
    for (int k = 0; k < 15; ++k) {
        conf_ok &= a.conf[k] >= 0.0 && a.conf[k] <= 1.0;
        mean_conf += a.conf[k] / 15.0;
    }
    CHECK(conf_ok && fabs(a.score - mean_conf) < 1e-12);
    printf("sketch %dx%d seed 21: confidence %.3f, PCK@0.1 %.2f, PCK@0.2 %.2f, head (%.1f, %.1f) vs true (%.1f, %.1f); "
           "2 threads identical\n",
           W, H, a.score, p1, p2, a.xy[0], a.xy[1], truth[0], truth[1]);
    skb_figure_info info;
    memset(&info, 0xAB, sizeof info);
    double xy[30], conf[15], score = 0.0;
    CHECK(skb_context_detect_figure(ctx, &g_img, NULL, xy, 30, conf, 15, &info) == SKB_OK);
    CHECK(memcmp(xy, a.xy, sizeof xy) == 0 && info.confidence == a.score);
    CHECK(info.backend == SKB_DETECTOR_FMP || info.backend == SKB_DETECTOR_BLAZEPOSE);
    CHECK(info.low_confidence == (info.confidence < SKB_LOW_CONFIDENCE ? 1u : 0u));
    CHECK(info.presence >= 0.5 && info.presence <= 1.0 && info.reserved == 0);
    printf("figure: backend %u, confidence %.3f, presence %.3f, low %u, %u other figure(s)\n", info.backend,
           info.confidence, info.presence, info.low_confidence, info.other_figures);
    /* The same detection with its facing: the same joints, four probabilities summing to 1, the
     * alternative the joints with left and right swapped (as skb_joints2d_swap_sides gives). */
    skb_facing_info facing;
    double xy2[30], conf2[15];
    CHECK(skb_context_detect_facing(ctx, &g_img, NULL, xy2, 30, conf2, 15, &info, &facing) == SKB_OK);
    CHECK(memcmp(xy, xy2, sizeof xy) == 0 && facing.facing <= SKB_FACING_UNKNOWN && facing.swapped <= 1u);
    double psum = facing.probabilities[0] + facing.probabilities[1] + facing.probabilities[2] + facing.probabilities[3];
    CHECK(fabs(psum - 1.0) < 1e-9 && facing.alternative_score >= 0.0 && facing.alternative_score <= 1.0);
    skb_joints2d mine, swapped;
    memcpy(mine.xy, xy2, sizeof xy2);
    memset(mine.visible, 1, sizeof mine.visible);
    mine.reserved = 0;
    CHECK(skb_joints2d_swap_sides(&mine, &swapped) == SKB_OK);
    CHECK(memcmp(swapped.xy, facing.alternative.xy, sizeof swapped.xy) == 0);
    CHECK(swapped.xy[4][0] == xy2[14] && swapped.xy[0][0] == xy2[0]); /* r_wrist <- l_wrist; head stays */
    printf("facing %u (front %.2f, back %.2f, left %.2f, right %.2f), swapped %u, alternative %.2f\n", facing.facing,
           facing.probabilities[0], facing.probabilities[1], facing.probabilities[2], facing.probabilities[3],
           facing.swapped, facing.alternative_score);

    skb_detect_options *o = NULL;
    CHECK(skb_detect_options_new(&o) == SKB_OK);
    CHECK(skb_detect_options_set_backend(o, SKB_DETECTOR_BLAZEPOSE) == SKB_OK);
    CHECK(skb_context_detect_figure(ctx, &g_img, o, xy, 30, conf, 15, &info) == SKB_OK);
    CHECK(info.backend == SKB_DETECTOR_BLAZEPOSE && pck(truth, xy, 0.2) >= 0.6);
    printf("blazepose alone: PCK@0.2 %.2f, confidence %.3f\n", pck(truth, xy, 0.2), info.confidence);
    CHECK(skb_detect_options_set_backend(o, 3) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_backend(NULL, 0) == SKB_ERR_NULL_POINTER);
    CHECK(skb_detect_options_set_strict(NULL, true) == SKB_ERR_NULL_POINTER);
    /* The sketch model's raw score, from a detector loaded by the caller (the embedded model's file). */
    skb_detector *det = NULL;
    CHECK(skb_detector_new_from_file(SKB_SOURCE_DIR "/assets/detector.skbd", &det) == SKB_OK);
    double raw = 0.0, score2 = 0.0;
    CHECK(skb_detector_detect(det, &g_img, NULL, NULL, NULL, xy, 30, conf, 15, &raw) == SKB_OK);
    /* Strict, the sketch model alone, a threshold above its best score: no figure, the score is
     * still reported, nothing else written. */
    CHECK(skb_detect_options_set_backend(o, SKB_DETECTOR_FMP) == SKB_OK);
    CHECK(skb_detect_options_set_strict(o, true) == SKB_OK);
    CHECK(skb_detect_options_set_threshold(o, raw + 1.0) == SKB_OK);
    memset(xy, 0xAB, sizeof xy);
    double sentinel = xy[0];
    CHECK(skb_context_detect(ctx, &g_img, o, xy, 30, conf, 15, &score) == SKB_ERR_NO_FIGURE);
    CHECK(fabs(score - raw) < 1e-9);
    CHECK(strstr(skb_last_error_message(), "no figure") != NULL);
    CHECK(memcmp(&xy[0], &sentinel, sizeof sentinel) == 0);
    printf("strict no figure ok: %s\n", skb_last_error_message());
    /* The same no-figure report from skb_detector_detect. */
    CHECK(skb_detector_detect(det, &g_img, o, NULL, NULL, xy, 30, conf, 15, &score2) == SKB_ERR_NO_FIGURE);
    CHECK(fabs(score2 - raw) < 1e-9);
    CHECK(memcmp(&xy[0], &sentinel, sizeof sentinel) == 0);
    skb_detector_free(det);
    skb_detector_free(NULL);
    printf("no figure from skb_detector_detect ok: score %.3f\n", raw);
    CHECK(skb_detect_options_set_strict(o, false) == SKB_OK);
    CHECK(skb_detect_options_set_threshold(o, NAN) == SKB_OK);
    CHECK(skb_detect_options_set_levels_per_octave(o, 5) == SKB_OK);
    CHECK(skb_context_detect(ctx, &g_img, o, xy, 30, conf, 15, &score) == SKB_OK);
    CHECK(pck(truth, xy, 0.2) >= 0.8);
    CHECK(skb_detect_options_set_levels_per_octave(o, 101) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_levels_per_octave(NULL, 5) == SKB_ERR_NULL_POINTER);
    CHECK(skb_detect_options_set_levels_per_octave(o, 7) == SKB_OK);
    CHECK(skb_detect_options_set_figure_range(o, 0.5, 0.5) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_figure_range(o, 0.0, 1.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_figure_range(o, NAN, 1.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_figure_range(o, 0.5, 1.0) == SKB_OK);
    CHECK(skb_detect_options_set_threshold(o, INFINITY) == SKB_ERR_NON_FINITE);
    CHECK(skb_detect_options_set_threshold(NULL, 0.0) == SKB_ERR_NULL_POINTER);
    /* Scales of the figure only (its cells are about height / 40 px): same answer, less work. */
    CHECK(skb_detect_options_set_scales(o, 4.0, 16.0) == SKB_OK);
    CHECK(skb_context_detect(ctx, &g_img, o, xy, 30, conf, 15, &score) == SKB_OK);
    CHECK(pck(truth, xy, 0.2) >= 0.8);
    CHECK(skb_detect_options_set_scales(o, 8.0, 8.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_scales(o, -1.0, 8.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_detect_options_set_scales(o, NAN, 8.0) == SKB_ERR_OUT_OF_RANGE);
    CHECK(strlen(skb_last_error_message()) > 0);
    /* A blank page holds no figure: the presence probability is the score. */
    uint8_t *blank = malloc(LEN);
    memset(blank, 255, LEN);
    skb_image page = {blank, W, H, STRIDE, 1};
    memset(xy, 0xAB, sizeof xy);
    CHECK(skb_context_detect(ctx, &page, NULL, xy, 30, conf, 15, &score) == SKB_ERR_NO_FIGURE);
    CHECK(score >= 0.0 && score < 0.5 && memcmp(&xy[0], &sentinel, sizeof sentinel) == 0);
    printf("blank page: no figure, presence %.3f\n", score);
    free(blank);

    /* Error paths: nothing written. */
    memset(xy, 0xAB, sizeof xy);
    CHECK(skb_context_detect(NULL, &g_img, o, xy, 30, conf, 15, &score) == SKB_ERR_NULL_POINTER);
    CHECK(skb_context_detect(ctx, NULL, o, xy, 30, conf, 15, &score) == SKB_ERR_NULL_POINTER);
    CHECK(skb_context_detect(ctx, &g_img, o, xy, 29, conf, 15, &score) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_context_detect(ctx, &g_img, o, xy, 30, conf, 14, &score) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_context_detect(ctx, &g_img, o, xy, 30, conf, 15, NULL) == SKB_ERR_NULL_POINTER);
    skb_image tiny = {px, 20, 20, STRIDE, 1};
    CHECK(skb_context_detect(ctx, &tiny, o, xy, 30, conf, 15, &score) == SKB_ERR_IMAGE_TOO_SMALL);
    skb_image bad_stride = {px, W, H, W - 1, 1};
    CHECK(skb_context_detect(ctx, &bad_stride, o, xy, 30, conf, 15, &score) == SKB_ERR_BAD_STRIDE);
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
