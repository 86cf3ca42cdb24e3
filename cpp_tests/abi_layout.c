/* Prints the layout of every public struct of sketchbody.h (size, and offset of each field) for
 * scripts/check-abi.sh, which compares it with the major version's baseline
 * (abi/sketchbody-MAJOR.layout): a struct of a released header never changes. */
#include <stddef.h>
#include <stdio.h>

#include <sketchbody.h>

#define SIZE(T) printf("layout %s size %zu\n", #T, sizeof(T))
#define FIELD(T, f) printf("layout %s.%s offset %zu\n", #T, #f, offsetof(T, f))

int main(void) {
    SIZE(skb_status);
    SIZE(skb_image);
    FIELD(skb_image, data);
    FIELD(skb_image, width);
    FIELD(skb_image, height);
    FIELD(skb_image, stride);
    FIELD(skb_image, channels);
    SIZE(skb_camera);
    FIELD(skb_camera, sx);
    FIELD(skb_camera, sy);
    FIELD(skb_camera, r);
    FIELD(skb_camera, t);
    SIZE(skb_joints2d);
    FIELD(skb_joints2d, xy);
    FIELD(skb_joints2d, visible);
    FIELD(skb_joints2d, reserved);
    SIZE(skb_pose3d);
    FIELD(skb_pose3d, joints);
    FIELD(skb_pose3d, sx);
    FIELD(skb_pose3d, sy);
    FIELD(skb_pose3d, r);
    FIELD(skb_pose3d, t);
    FIELD(skb_pose3d, rms_px);
    FIELD(skb_pose3d, length_excess);
    FIELD(skb_pose3d, prior_weight);
    FIELD(skb_pose3d, weights);
    FIELD(skb_pose3d, num_bases);
    FIELD(skb_pose3d, bases);
    FIELD(skb_pose3d, reserved);
    SIZE(skb_pose_figure);
    FIELD(skb_pose_figure, factors);
    FIELD(skb_pose_figure, plausible);
    FIELD(skb_pose_figure, reserved);
    SIZE(skb_figure_info);
    FIELD(skb_figure_info, backend);
    FIELD(skb_figure_info, low_confidence);
    FIELD(skb_figure_info, confidence);
    FIELD(skb_figure_info, presence);
    FIELD(skb_figure_info, other_figures);
    FIELD(skb_figure_info, reserved);
    SIZE(skb_facing_info);
    FIELD(skb_facing_info, facing);
    FIELD(skb_facing_info, swapped);
    FIELD(skb_facing_info, probabilities);
    FIELD(skb_facing_info, alternative_score);
    FIELD(skb_facing_info, alternative);
    return 0;
}
