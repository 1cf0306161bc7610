/*
 * A QEMU TCG plugin that counts executed guest instructions exactly: in total and per
 * translation block, written at exit as "total N" then one "ADDRESS INSTRUCTIONS" line per
 * block start (profile.sh maps them to functions).
 *
 * Debian's QEMU 7.2 loads plugins but ships no plugin header, so the few entry points used
 * are declared here as QEMU 7.2's plugin API (version 1) defines them.
 *
 * Build: cc -shared -fPIC -O2 -o libinsns.so insns.c
 * Use:   qemu-system-arm ... -plugin ./libinsns.so,out=FILE
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
typedef struct qemu_info_t qemu_info_t;
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*tb_trans_cb)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);
typedef void (*udata_cb)(qemu_plugin_id_t id, void *userdata);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, tb_trans_cb cb);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb *tb, enum qemu_plugin_op op,
                                              void *ptr, uint64_t imm);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, udata_cb cb, void *userdata);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
uint64_t qemu_plugin_tb_vaddr(const struct qemu_plugin_tb *tb);

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

/* One translation of a block: where it starts, its length, how often it ran. */
struct block {
    uint64_t vaddr, insns, runs;
    struct block *next;
};

static struct block *blocks;
static char out_path[4096] = "insns.txt";

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    struct block *b = calloc(1, sizeof *b);
    if (!b) {
        abort();
    }
    b->vaddr = qemu_plugin_tb_vaddr(tb);
    b->insns = qemu_plugin_tb_n_insns(tb);
    b->next = blocks;
    blocks = b;
    qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &b->runs, 1);
}

static void write_counts(qemu_plugin_id_t id, void *userdata) {
    FILE *f = fopen(out_path, "w");
    if (!f) {
        perror(out_path);
        return;
    }
    uint64_t total = 0;
    for (struct block *b = blocks; b; b = b->next) {
        total += b->insns * b->runs;
    }
    fprintf(f, "total %llu\n", (unsigned long long)total);
    for (struct block *b = blocks; b; b = b->next) {
        if (b->runs) {
            fprintf(f, "%llx %llu\n", (unsigned long long)b->vaddr,
                    (unsigned long long)(b->insns * b->runs));
        }
    }
    fclose(f);
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id,
                                                               const qemu_info_t *info, int argc,
                                                               char **argv) {
    for (int i = 0; i < argc; i++) {
        if (strncmp(argv[i], "out=", 4) == 0 && strlen(argv[i] + 4) < sizeof out_path) {
            strcpy(out_path, argv[i] + 4);
        }
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    qemu_plugin_register_atexit_cb(id, write_counts, NULL);
    return 0;
}
