// Where the threads of a process are: for each thread ID given, 5 samples of its instruction
// pointer and of the code addresses near the top of its stack, each as a file and an offset in
// it (a rough backtrace: a stack slot that points into executable code is most often a return
// address). `scripts/gpu-check.sh hunt` runs it on the threads of a hung test; `pack` builds it
// static, so that it runs on a GPU machine without gdb. Usage: thread_pcs PID TID...
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/ptrace.h>
#include <sys/user.h>
#include <sys/wait.h>
#include <unistd.h>

// The mappings of a process, read once per sample.
struct mapping {
    unsigned long long lo, hi, off;
    int exec;
    char file[256];
};
static struct mapping maps[4096];
static int nmaps;

static void read_maps(int pid) {
    char path[64];
    snprintf(path, sizeof path, "/proc/%d/maps", pid);
    FILE *f = fopen(path, "r");
    nmaps = 0;
    if (!f) return;
    char line[512];
    while (nmaps < 4096 && fgets(line, sizeof line, f)) {
        struct mapping *m = &maps[nmaps];
        char perm[8], dev[16];
        unsigned long inode;
        m->file[0] = 0;
        if (sscanf(line, "%llx-%llx %7s %llx %15s %lu %255s", &m->lo, &m->hi, perm, &m->off, dev,
                   &inode, m->file) >= 6) {
            m->exec = perm[2] == 'x';
            nmaps++;
        }
    }
    fclose(f);
}

// Print "file +offset" for `addr` and return 1 when a mapping holds it (an executable one when
// `code_only`); return 0 and print nothing otherwise.
static int describe(unsigned long long addr, int code_only, const char *prefix) {
    for (int i = 0; i < nmaps; i++) {
        const struct mapping *m = &maps[i];
        if (addr >= m->lo && addr < m->hi && (!code_only || m->exec)) {
            printf("%s%s +0x%llx\n", prefix, m->file[0] ? m->file : "[anonymous]",
                   addr - m->lo + m->off);
            return 1;
        }
    }
    return 0;
}

static void sample(int pid, int tid) {
    if (ptrace(PTRACE_SEIZE, tid, 0, 0) != 0) {
        printf("  thread %d: cannot attach (%d)\n", tid, errno);
        return;
    }
    ptrace(PTRACE_INTERRUPT, tid, 0, 0);
    int status;
    waitpid(tid, &status, __WALL);
    read_maps(pid);
    struct user_regs_struct regs;
    ptrace(PTRACE_GETREGS, tid, 0, &regs);
    printf("  rip %llx: ", regs.rip);
    if (!describe(regs.rip, 0, "")) printf("not in a mapping\n");
    int shown = 0;
    for (int i = 0; i < 4096 && shown < 24; i++) {
        errno = 0;
        long word = ptrace(PTRACE_PEEKDATA, tid, (void *)(regs.rsp + 8 * (unsigned long long)i), 0);
        if (errno) break;
        char prefix[32];
        snprintf(prefix, sizeof prefix, "    stack[%d] ", i);
        shown += describe((unsigned long long)word, 1, prefix);
    }
    ptrace(PTRACE_DETACH, tid, 0, 0);
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: thread_pcs PID TID...\n");
        return 2;
    }
    int pid = atoi(argv[1]);
    for (int t = 2; t < argc; t++) {
        int tid = atoi(argv[t]);
        for (int s = 0; s < 5; s++) {
            printf("thread %d, sample %d\n", tid, s);
            sample(pid, tid);
            usleep(200000);
        }
    }
    return 0;
}
