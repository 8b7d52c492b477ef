/* QEMU TCG plugin: guest instructions executed inside address ranges, per range and per call.
 *
 * Used by kernel_icount.py to measure each dense kernel of the flight image separately (qemu-system-arm
 * 7.2, `-icount shift=0`). Debian ships no qemu-plugin.h, so the few declarations used are repeated here
 * (plugin API version 1, as in QEMU 7.2's include/qemu/qemu-plugin.h).
 *
 * Environment: ICOUNT_CFG names a file of lines "name start end" (hex addresses, end exclusive; the first
 * range is the dump trigger), ICOUNT_OUT the report, rewritten at every entry of the first range (QEMU
 * is killed, not exited, at the end of a run). Report lines: "range NAME INSTRUCTIONS ENTRIES", then
 * "enter NAME" for the first MAX_LOG entries into any range, in order.
 *
 * Build: gcc -O2 -shared -fPIC -fvisibility=hidden -o libicount.so icount.c */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS };
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t, struct qemu_plugin_tb *);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int, void *);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t, qemu_plugin_vcpu_tb_trans_cb_t);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
void qemu_plugin_register_vcpu_insn_exec_inline(struct qemu_plugin_insn *, enum qemu_plugin_op, void *,
                                                uint64_t);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *, qemu_plugin_vcpu_udata_cb_t,
                                            enum qemu_plugin_cb_flags, void *);
__attribute__((visibility("default"))) int qemu_plugin_version = 1;

#define MAX_RANGES 128
#define MAX_LOG 1000
static struct {
    char name[200];
    uint64_t lo, hi, count, entries;
} ranges[MAX_RANGES];
static int n_ranges;
static int entered[MAX_LOG];
static int n_entered;
static const char *out_path;

static void dump(void) {
    FILE *f = fopen(out_path, "w");
    if (!f) return;
    for (int i = 0; i < n_ranges; i++)
        fprintf(f, "range %s %llu %llu\n", ranges[i].name, (unsigned long long)ranges[i].count,
                (unsigned long long)ranges[i].entries);
    for (int i = 0; i < n_entered; i++) fprintf(f, "enter %s\n", ranges[entered[i]].name);
    fclose(f);
}

static void on_entry(unsigned int vcpu, void *userdata) {
    int i = (int)(intptr_t)userdata;
    (void)vcpu;
    if (n_entered < MAX_LOG) entered[n_entered++] = i;
    ranges[i].entries++;
    if (i == 0) dump();
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    (void)id;
    for (size_t k = 0; k < qemu_plugin_tb_n_insns(tb); k++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, k);
        uint64_t pc = qemu_plugin_insn_vaddr(insn);
        for (int i = 0; i < n_ranges; i++) {
            if (pc < ranges[i].lo || pc >= ranges[i].hi) continue;
            qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &ranges[i].count, 1);
            if (pc == ranges[i].lo)
                qemu_plugin_register_vcpu_insn_exec_cb(insn, on_entry, QEMU_PLUGIN_CB_NO_REGS,
                                                       (void *)(intptr_t)i);
        }
    }
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info,
                                                               int argc, char **argv) {
    (void)info, (void)argc, (void)argv;
    const char *cfg = getenv("ICOUNT_CFG");
    out_path = getenv("ICOUNT_OUT");
    if (!cfg || !out_path) return 1;
    FILE *f = fopen(cfg, "r");
    if (!f) return 1;
    unsigned long long lo, hi;
    while (n_ranges < MAX_RANGES && fscanf(f, "%199s %llx %llx", ranges[n_ranges].name, &lo, &hi) == 3) {
        ranges[n_ranges].lo = lo;
        ranges[n_ranges].hi = hi;
        n_ranges++;
    }
    fclose(f);
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    return 0;
}
