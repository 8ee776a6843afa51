/* Opens a scene image through the C ABI and prints what it holds, or why it cannot be
 * opened (exit 1). Built by CI with gcc -Wall -Wextra -Werror against the static library:
 *
 *     cargo build -p hirad-ffi
 *     gcc -Wall -Wextra -Werror -Iffi/include ffi/examples/open.c target/debug/libhirad_ffi.a -lpthread -ldl -lm -o open
 *     ./open scene.hirb
 */
#include "hirad.h"

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s SCENE.hirb\n", argv[0]);
        return 2;
    }
    FILE *f = fopen(argv[1], "rb");
    if (!f) {
        perror(argv[1]);
        return 2;
    }
    size_t cap = 1 << 16, len = 0;
    uint8_t *bytes = malloc(cap);
    size_t n;
    while (bytes && (n = fread(bytes + len, 1, cap - len, f)) > 0) {
        len += n;
        if (len == cap) {
            uint8_t *more = realloc(bytes, cap * 2);
            if (!more) {
                free(bytes);
                bytes = NULL;
                break;
            }
            bytes = more;
            cap *= 2;
        }
    }
    fclose(f);
    if (!bytes) {
        fprintf(stderr, "%s: out of memory\n", argv[1]);
        return 2;
    }
    HiradScene *scene = NULL;
    HiradStatus status = hirad_scene_open_memory(bytes, len, &scene);
    free(bytes); /* the handle keeps its own copy */
    int code = 0;
    if (status == HIRAD_STATUS_OK) {
        HiradSceneInfo info;
        if (hirad_scene_info(scene, &info) == HIRAD_STATUS_OK) {
            printf("bands %" PRIu32 "\npolygons %" PRIu32 "\nexpanded polygons %" PRIu64
                   "\noriginals %" PRIu32 "\ninstances %" PRIu32 "\n",
                   info.bands, info.polygons, info.expanded_polygons, info.originals,
                   info.instances);
        } else {
            code = 1;
        }
    } else {
        fprintf(stderr, "%s: %s (status %d, byte %" PRIu64 ")\n", argv[1],
                hirad_scene_message(scene), (int)status, hirad_scene_error_offset(scene));
        code = 1;
    }
    hirad_scene_free(scene);
    return code;
}
