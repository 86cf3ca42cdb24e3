/* A minimal plug-in (a loadable module) linking libsketchbody.a, for the `gnu_stack` test
 * (scripts/check-gnu-stack.sh): its one entry point reaches the detector, so the link pulls in
 * tract's assembly kernels, whose objects decide whether the plug-in's stack is executable. */
#include <sketchbody.h>

/* Detects the figure in `image` with the embedded backends; the status of skb_context_detect. */
__attribute__((visibility("default"))) skb_status plugin_detect(const struct skb_context *ctx, const skb_image *image,
                                                               double *joints_xy, double *confidence, double *score) {
    return skb_context_detect(ctx, image, NULL, joints_xy, 30, confidence, 15, score);
}
