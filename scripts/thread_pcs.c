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

// Print "file +offset" for `addr` and return 1 when an executable mapping of `pid` holds it
// (any mapping when `code_only` is 0); return 0 and print nothing otherwise.
static int describe(int pid, unsigned long long addr, int code_only, const char *prefix) {
    char path[64];
    snprintf(path, sizeof path, "/proc/%d/maps", pid);
    FILE *maps = fopen(path, "r");
    if (!maps) return 0;
    char line[512];
    int found = 0;
    while (fgets(line, sizeof line, maps)) {
        unsigned long long lo, hi, off;
        unsigned long inode;
        char perm[8], dev[16], file[400] = "";
        int fields = sscanf(line, "%llx-%llx %7s %llx %15s %lu %399s", &lo, &hi, perm, &off, dev,
                            &inode, file);
        if (fields >= 6 && addr >= lo && addr < hi && (!code_only || perm[2] == 'x')) {
            printf("%s%s +0x%llx\n", prefix, file[0] ? file : "[anonymous]", addr - lo + off);
            found = 1;
            break;
        }
    }
    fclose(maps);
    return found;
}

static void sample(int pid, int tid) {
    if (ptrace(PTRACE_SEIZE, tid, 0, 0) != 0) {
        printf("  thread %d: cannot attach (%d)\n", tid, errno);
        return;
    }
    ptrace(PTRACE_INTERRUPT, tid, 0, 0);
    int status;
    waitpid(tid, &status, __WALL);
    struct user_regs_struct regs;
    ptrace(PTRACE_GETREGS, tid, 0, &regs);
    printf("  rip %llx: ", regs.rip);
    if (!describe(pid, regs.rip, 0, "")) printf("not in a mapping\n");
    int shown = 0;
    for (int i = 0; i < 4096 && shown < 24; i++) {
        errno = 0;
        long word = ptrace(PTRACE_PEEKDATA, tid, (void *)(regs.rsp + 8 * (unsigned long long)i), 0);
        if (errno) break;
        char prefix[32];
        snprintf(prefix, sizeof prefix, "    stack[%d] ", i);
        shown += describe(pid, (unsigned long long)word, 1, prefix);
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
