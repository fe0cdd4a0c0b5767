/* insn_count: a qemu-user TCG plugin that counts guest instructions executed, for the instruction
 * budgets of the timing tests (docs/budgets.md). Debian's qemu-user 7.2 is built with plugin support
 * but ships neither plugins nor qemu-plugin.h, so this file declares the few entry points it uses from
 * QEMU's public plugin API, version 1 (include/qemu/qemu-plugin.h in QEMU 7.2).
 *
 *   qemu-sparc32plus -plugin build/insn_count.so,out=FILE ./program
 *
 * writes "insns N" to FILE (or stderr) at exit. Counting is inline (one add per translated block),
 * exact for single-threaded guests; with several guest threads the count may lose increments.
 *
 * Regions: a guest program brackets the code under test with the marker syscall 0x1f00 (unused on
 * aarch64, arm and sparc: qemu returns -ENOSYS), syscall(0x1f00, 1, id) to begin region id and
 * syscall(0x1f00, 2, id) to end it (test/timing/region.hpp). For each region id (< 256) the plugin
 * prints, after "insns N":
 *   region ID calls C total T min A max B
 * with the instructions between each begin and its end (the marker's own syscall path included, a
 * few dozen instructions; an empty region measures it). Start-up, argv parsing and printing stay out.
 *
 * Profile: with profile=FILE the plugin also counts, per translated block, the instructions it
 * executed while any region was open, and writes "VADDR INSNS" lines (hex address, decimal count) to
 * FILE at exit; scripts/timing --profile maps the addresses to functions with the target's nm. */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t {
  const char* target_name;
  struct {
    int min;
    int cur;
  } version;
  bool system_emulation;
  union {
    struct {
      int smp_vcpus;
      int max_vcpus;
    } system;
  };
} qemu_info_t;
struct qemu_plugin_tb;
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb* tb);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void* userdata);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb* tb, enum qemu_plugin_op op, void* ptr,
                                              uint64_t imm);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb* tb);
uint64_t qemu_plugin_tb_vaddr(const struct qemu_plugin_tb* tb);
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS };
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void* userdata);
void qemu_plugin_register_vcpu_tb_exec_cb(struct qemu_plugin_tb* tb, qemu_plugin_vcpu_udata_cb_t cb,
                                          enum qemu_plugin_cb_flags flags, void* userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void* userdata);
typedef void (*qemu_plugin_vcpu_syscall_cb_t)(qemu_plugin_id_t id, unsigned int vcpu_index, int64_t num, uint64_t a1,
                                              uint64_t a2, uint64_t a3, uint64_t a4, uint64_t a5, uint64_t a6,
                                              uint64_t a7, uint64_t a8);
void qemu_plugin_register_vcpu_syscall_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_syscall_cb_t cb);

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

static uint64_t g_insns;
static char g_out[4096];

enum { kMarkerSyscall = 0x1f00, kBegin = 1, kEnd = 2, kMaxRegions = 256 };
struct region {
  uint64_t calls, total, min, max, begin;
  int open;
};
static struct region g_regions[kMaxRegions];
static uint64_t g_unmatched;  /* an end without a begin, a begin while open, or an id out of range */
static int g_open_regions;

/* profile=FILE: one record per translated block (a block translated twice gets two records; the
 * mapping script sums by address). */
struct block {
  uint64_t vaddr, insns, in_region;
  struct block* next;
};
static char g_profile[4096];
static struct block* g_blocks;

static void on_block_exec(unsigned int vcpu, void* udata) {
  (void)vcpu;
  struct block* b = (struct block*)udata;
  if (g_open_regions > 0) b->in_region += b->insns;
}

static void on_syscall(qemu_plugin_id_t id, unsigned int vcpu, int64_t num, uint64_t a1, uint64_t a2, uint64_t a3,
                       uint64_t a4, uint64_t a5, uint64_t a6, uint64_t a7, uint64_t a8) {
  (void)id, (void)vcpu, (void)a3, (void)a4, (void)a5, (void)a6, (void)a7, (void)a8;
  if (num != kMarkerSyscall) return;
  if (a2 >= kMaxRegions) {
    ++g_unmatched;
    return;
  }
  struct region* r = &g_regions[a2];
  if (a1 == kBegin && !r->open) {
    r->open = 1;
    ++g_open_regions;
    r->begin = g_insns;
  } else if (a1 == kEnd && r->open) {
    const uint64_t n = g_insns - r->begin;
    r->open = 0;
    --g_open_regions;
    if (r->calls == 0 || n < r->min) r->min = n;
    if (n > r->max) r->max = n;
    r->total += n;
    ++r->calls;
  } else {
    ++g_unmatched;
  }
}

static void on_tb_translate(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &g_insns, qemu_plugin_tb_n_insns(tb));
  if (g_profile[0]) {
    struct block* b = (struct block*)calloc(1, sizeof *b);
    if (b == NULL) return;
    b->vaddr = qemu_plugin_tb_vaddr(tb);
    b->insns = qemu_plugin_tb_n_insns(tb);
    b->next = g_blocks;
    g_blocks = b;
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_block_exec, QEMU_PLUGIN_CB_NO_REGS, b);
  }
}

static void on_exit_cb(qemu_plugin_id_t id, void* userdata) {
  (void)id;
  (void)userdata;
  FILE* f = g_out[0] ? fopen(g_out, "w") : stderr;
  if (f == NULL) f = stderr;
  fprintf(f, "insns %llu\n", (unsigned long long)g_insns);
  for (int i = 0; i < kMaxRegions; ++i) {
    const struct region* r = &g_regions[i];
    if (r->calls == 0) continue;
    fprintf(f, "region %d calls %llu total %llu min %llu max %llu\n", i, (unsigned long long)r->calls,
            (unsigned long long)r->total, (unsigned long long)r->min, (unsigned long long)r->max);
  }
  if (g_unmatched) fprintf(f, "region-errors %llu\n", (unsigned long long)g_unmatched);
  if (f != stderr) fclose(f);
  if (g_profile[0]) {
    FILE* p = fopen(g_profile, "w");
    if (p == NULL) {
      fprintf(stderr, "insn_count: cannot write the profile to %s\n", g_profile);
      return;
    }
    for (const struct block* b = g_blocks; b != NULL; b = b->next)
      if (b->in_region) fprintf(p, "%llx %llu\n", (unsigned long long)b->vaddr, (unsigned long long)b->in_region);
    fclose(p);
  }
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t* info, int argc,
                                                               char** argv) {
  (void)info;
  for (int i = 0; i < argc; ++i) {
    if (strncmp(argv[i], "out=", 4) == 0) {
      strncpy(g_out, argv[i] + 4, sizeof g_out - 1);
    } else if (strncmp(argv[i], "profile=", 8) == 0) {
      strncpy(g_profile, argv[i] + 8, sizeof g_profile - 1);
    } else {
      fprintf(stderr, "insn_count: unknown argument '%s' (out=FILE, profile=FILE)\n", argv[i]);
      return -1;
    }
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_tb_translate);
  qemu_plugin_register_vcpu_syscall_cb(id, on_syscall);
  qemu_plugin_register_atexit_cb(id, on_exit_cb, NULL);
  return 0;
}
