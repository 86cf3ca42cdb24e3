/* Benchmark, not a test (docs/benchmarks.md, "Re-pose"): the time of the C API's re-pose calls on
 * a fitted result, as a host calls them while the artist works (issue 46 item 3, issue 50 item 2).
 *
 *   repose_bench SKETCH JOINTS [REPS]
 *
 * Runs skb_pipeline_run once on SKETCH with JOINTS (the library's default fit), then times, REPS
 * times each (default 41), with the calls interleaved so that a busy machine slows them alike:
 *   - skb_result_repose_joints: the right wrist moved by a few pixels back and forth (a drag);
 *   - skb_result_flip_limb: the first limb with depth flipped;
 *   - skb_result_pick_alternative: alternatives 1 and 0 in turn;
 *   - skb_pose_estimate_flip_limb on a pose estimate handle (no body);
 *   - skb_pose_estimate_new (the 3-D pose with its alternatives, no body).
 * Prints the median and the minimum of each, wall ms per call, and the process's CPU ms per call
 * (all threads: skinning runs on the library's thread pool).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sketchbody.h"

enum { KINDS = 5, MAX_REPS = 1001 };
static const char *NAMES[KINDS] = {"skb_result_repose_joints (a dragged wrist)", "skb_result_flip_limb",
                                   "skb_result_pick_alternative", "skb_pose_estimate_flip_limb (estimate handle)",
                                   "skb_pose_estimate_new (pose + alternatives)"};

static double now(clockid_t clock) {
    struct timespec t;
    clock_gettime(clock, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

#define MUST(call)                                                                                  \
    do {                                                                                            \
        if ((call) != SKB_OK) {                                                                     \
            fprintf(stderr, "%s:%d: %s failed: %s\n", __FILE__, __LINE__, #call, skb_last_error_message()); \
            return 1;                                                                               \
        }                                                                                           \
    } while (0)

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s SKETCH JOINTS [REPS]\n", argv[0]);
        return 2;
    }
    int reps = argc > 3 ? atoi(argv[3]) : 41;
    if (reps < 1 || reps > MAX_REPS) {
        fprintf(stderr, "REPS must be 1..%d\n", MAX_REPS);
        return 2;
    }
    skb_context *ctx = NULL;
    MUST(skb_context_new(&ctx));
    skb_gray_image *sketch = NULL;
    MUST(skb_gray_image_new_from_file(argv[1], &sketch));
    skb_image view;
    MUST(skb_gray_image_view(sketch, &view));
    skb_joints2d joints;
    MUST(skb_joints2d_read_json(argv[2], &joints));
    skb_pose_dictionary *dict = NULL;
    MUST(skb_pose_dictionary_new_default(&dict));
    skb_result *result = NULL;
    MUST(skb_pipeline_run(ctx, &view, &joints, dict, NULL, NULL, NULL, NULL, &result));

    uint32_t flip = SKB_NUM_LIMBS, outcome = 0;
    for (uint32_t l = 0; l < SKB_NUM_LIMBS && flip == SKB_NUM_LIMBS; l++) {
        MUST(skb_result_flip_limb(result, l, &outcome));
        if (outcome == SKB_REPOSE_DONE) {
            flip = l;
            MUST(skb_result_flip_limb(result, l, &outcome));
        }
    }
    if (flip == SKB_NUM_LIMBS) {
        fprintf(stderr, "no limb of the example's pose has depth to flip\n");
        return 1;
    }
    skb_pose_estimate *est = NULL;
    MUST(skb_pose_estimate_new_from_result(result, &est));

    static double wall[KINDS][MAX_REPS], cpu[KINDS][MAX_REPS];
    skb_joints2d moved = joints;
    for (int r = 0; r < reps; r++) {
        for (int k = 0; k < KINDS; k++) {
            double w0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_PROCESS_CPUTIME_ID);
            switch (k) {
            case 0:
                moved.xy[4][0] = joints.xy[4][0] + ((r % 2) ? 6.0 : -6.0);
                moved.xy[4][1] = joints.xy[4][1] - 0.5 * (double)(r % 5);
                MUST(skb_result_repose_joints(result, dict, &moved, &outcome));
                break;
            case 1: /* the first limb with depth in the pose case 0 left (a flat one is a no-op) */
                outcome = SKB_REPOSE_NO_DEPTH;
                for (uint32_t l = 0; l < SKB_NUM_LIMBS && outcome == SKB_REPOSE_NO_DEPTH; l++)
                    MUST(skb_result_flip_limb(result, l, &outcome));
                break;
            case 2:
                MUST(skb_result_pick_alternative(result, (uint32_t)((r + 1) % 2), &outcome));
                break;
            case 3:
                MUST(skb_pose_estimate_flip_limb(est, flip, &outcome));
                break;
            default: {
                skb_pose_estimate *e = NULL;
                MUST(skb_pose_estimate_new(dict, &joints, NULL, &e));
                skb_pose_estimate_free(e);
            }
            }
            wall[k][r] = 1e3 * (now(CLOCK_MONOTONIC) - w0);
            cpu[k][r] = 1e3 * (now(CLOCK_PROCESS_CPUTIME_ID) - c0);
            if (outcome != SKB_REPOSE_DONE) {
                fprintf(stderr, "%s: outcome %u\n", NAMES[k], outcome);
                return 1;
            }
        }
    }
    printf("%-46s %10s %10s %10s  (%d calls each)\n", "call", "median ms", "min ms", "CPU ms all", reps);
    for (int k = 0; k < KINDS; k++) {
        double c = 0;
        for (int r = 0; r < reps; r++) c += cpu[k][r];
        qsort(wall[k], (size_t)reps, sizeof(double), cmp);
        printf("%-46s %10.3f %10.3f %10.3f\n", NAMES[k], wall[k][reps / 2], wall[k][0], c / reps);
    }
    skb_pose_estimate_free(est);
    skb_result_free(result);
    skb_pose_dictionary_free(dict);
    skb_gray_image_free(sketch);
    skb_context_free(ctx);
    return 0;
}
