/* Clean stops of batch runs (SIGINT/SIGTERM set a flag the loops read) and
 * their output folders (refused when they already hold files, removed again
 * when a run fails before writing). */
#define _POSIX_C_SOURCE 200809L
#include "mr_core.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Process-wide by nature: a signal reaches the process, not a context. */
static volatile sig_atomic_t g_stop_signal = 0;

static void on_stop_signal(int sig) {
    if (g_stop_signal) {
        /* Asked twice: the run is stuck or the user insists. */
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    g_stop_signal = sig;
}

void mr_stop_catch(void) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

bool mr_stop_requested(void) { return g_stop_signal != 0; }
int mr_stop_signal(void) { return (int)g_stop_signal; }
void mr_stop_request(int sig) { g_stop_signal = sig; }

/* ------------------------------------------------------- output folders */

bool mr_dir_has_entries(const char *path) {
    DIR *d = opendir(path);
    if (!d) return false;
    bool any = false;
    for (struct dirent *e; !any && (e = readdir(d));)
        any = strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return any;
}

bool mr_outdir_check(const char *path, bool force, mr_error *err) {
    if (!path || !path[0]) return mr_fail(err, MR_ERR_INVALID, "no output folder given");
    struct stat st;
    if (stat(path, &st) != 0) return true; /* made when the run writes */
    if (!S_ISDIR(st.st_mode)) return mr_fail(err, MR_ERR_IO, "%s exists and is not a folder", path);
    if (!force && mr_dir_has_entries(path))
        return mr_fail(err, MR_ERR_INVALID, "%s is not empty (--force writes into it anyway)", path);
    return true;
}

bool mr_outdir_create(mr_outdir *d, const char *path, bool force, mr_error *err) {
    memset(d, 0, sizeof *d);
    if (!mr_outdir_check(path, force, err)) return false;
    if (strlen(path) >= sizeof d->path) return mr_fail(err, MR_ERR_IO, "path too long: %s", path);
    snprintf(d->path, sizeof d->path, "%s", path);
    /* The topmost missing folder on the way down is the one this run makes. */
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", path);
    for (size_t i = 1, n = strlen(buf); i <= n; i++) {
        if (buf[i] != '/' && buf[i] != 0) continue;
        char c = buf[i];
        buf[i] = 0;
        if (!mr_file_exists(buf)) {
            snprintf(d->made, sizeof d->made, "%s", buf);
            buf[i] = c;
            break;
        }
        buf[i] = c;
    }
    return mr_mkdirs(path, err);
}

void mr_outdir_abandon(mr_outdir *d) {
    if (!d->made[0]) return;
    /* From the leaf up to the folder this run made; rmdir leaves any
     * folder that holds something. */
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", d->path);
    size_t top = strlen(d->made);
    for (;;) {
        size_t n = strlen(buf);
        while (n > 1 && buf[n - 1] == '/') buf[--n] = 0;
        if (rmdir(buf) != 0 || n <= top) break;
        char *slash = strrchr(buf, '/');
        if (!slash) break;
        *slash = 0;
    }
    d->made[0] = 0;
}
