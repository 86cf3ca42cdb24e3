/* The packaging consumer: a program outside the sketchbody tree that includes <sketchbody.h>,
 * checks the header and library versions agree, and builds the mean female mesh. Built three
 * ways by cpp_tests/consumer/run.sh (find_package, pkg-config, add_subdirectory), each shared
 * and static; prints one line and exits non-zero on any failure. */
#include <sketchbody.h>

#include <stdio.h>
#include <string.h>

#ifndef SKB_CONSUMER_HOW
#define SKB_CONSUMER_HOW "unnamed"
#endif

int main(void) {
    const char *lib = skb_version();
    if (lib == NULL || strcmp(lib, SKB_VERSION_STRING) != 0) {
        fprintf(stderr, "consumer %s: header %s, library %s\n", SKB_CONSUMER_HOW, SKB_VERSION_STRING,
                lib ? lib : "(null)");
        return 1;
    }
    struct skb_context *ctx = NULL;
    if (skb_context_new(&ctx) != SKB_OK) {
        fprintf(stderr, "consumer %s: skb_context_new failed\n", SKB_CONSUMER_HOW);
        return 1;
    }
    struct skb_mesh *mesh = NULL;
    size_t vertices = 0, faces = 0, joints = 0;
    int ok = skb_mesh_new_from_shape(ctx, SKB_GENDER_FEMALE, NULL, 0, &mesh) == SKB_OK &&
             skb_mesh_vertex_count(mesh, &vertices) == SKB_OK && skb_mesh_face_count(mesh, &faces) == SKB_OK &&
             skb_mesh_joint_count(mesh, &joints) == SKB_OK && vertices > 0 && faces > 0 && joints > 0;
    skb_mesh_free(mesh);
    skb_context_free(ctx);
    if (!ok) {
        fprintf(stderr, "consumer %s: building the mean mesh failed\n", SKB_CONSUMER_HOW);
        return 1;
    }
    printf("consumer %s: sketchbody %s, mean female mesh %zu vertices, %zu faces, %zu joints\n", SKB_CONSUMER_HOW,
           lib, vertices, faces, joints);
    return 0;
}
