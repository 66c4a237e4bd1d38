/* /init of the arm64 guest's first-boot initramfs (hil-tests/vm/README.md "arm64 guest").
 *
 * Debian's arm64 kernel has virtio_blk and ext4 as modules, and a `debootstrap --foreign` root
 * cannot make an initrd on a host without binfmt_misc (initramfs-tools runs the target's
 * programs). This program, built static for aarch64 by build-base.sh, is that initrd's only
 * executable. Contract:
 *  1. mounts devtmpfs on /dev and proc on /proc, writes to /dev/console;
 *  2. loads, in order, the modules named one per line in /modules (paths inside the
 *     initramfs; build-base.sh orders them after modules.dep: dependencies first) with
 *     finit_module(2); a module already present (EEXIST) is not an error;
 *  3. waits up to 60 s for /dev/vda, mounts it (ext4, read-write) on /root;
 *  4. moves /dev into it, makes it the root (MS_MOVE + chroot, what klibc's run-init does
 *     minus freeing the initramfs) and executes the kernel command line's init= (default
 *     /sbin/init) with no arguments.
 * On any failure it prints what failed and why on the console and exits: the kernel panics,
 * and with panic=-1 and QEMU's -no-reboot the VM ends (build-base.sh reports the console).
 */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

static int fail(const char *what, const char *arg) {
  fprintf(stderr, "navd-vm first-boot init: %s %s: %s\n", what, arg, strerror(errno));
  return 1;
}

static int load_modules(const char *list_path) {
  char line[512];
  FILE *list = fopen(list_path, "r");
  if (!list) return fail("cannot open the module list", list_path);
  while (fgets(line, sizeof line, list)) {
    line[strcspn(line, "\n")] = '\0';
    if (line[0] == '\0') continue;
    int fd = open(line, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return fail("cannot open module", line);
    if (syscall(SYS_finit_module, fd, "", 0) != 0 && errno != EEXIST)
      return fail("cannot load module", line);
    close(fd);
  }
  fclose(list);
  return 0;
}

/* The value of init= on the kernel command line, or /sbin/init. */
static void init_path(char *out, size_t size) {
  char cmdline[4096] = {0};
  FILE *f = fopen("/proc/cmdline", "r");
  snprintf(out, size, "/sbin/init");
  if (!f) return;
  if (fgets(cmdline, sizeof cmdline, f)) {
    for (char *tok = strtok(cmdline, " \n"); tok; tok = strtok(NULL, " \n"))
      if (strncmp(tok, "init=", 5) == 0) snprintf(out, size, "%s", tok + 5);
  }
  fclose(f);
}

int main(void) {
  struct stat st;
  char init[256];
  mkdir("/dev", 0755);
  mkdir("/proc", 0555);
  mkdir("/root", 0700);
  if (mount("devtmpfs", "/dev", "devtmpfs", 0, NULL) != 0) return fail("mount", "/dev");
  if (mount("proc", "/proc", "proc", 0, NULL) != 0) return fail("mount", "/proc");
  int console = open("/dev/console", O_RDWR);
  if (console >= 0) {
    dup2(console, 0); dup2(console, 1); dup2(console, 2);
  }
  if (load_modules("/modules") != 0) return 1;
  for (int i = 0; i < 600 && stat("/dev/vda", &st) != 0; ++i) usleep(100000);
  if (mount("/dev/vda", "/root", "ext4", 0, NULL) != 0) return fail("mount", "/dev/vda");
  init_path(init, sizeof init);
  umount("/proc");
  if (mount("/dev", "/root/dev", NULL, MS_MOVE, NULL) != 0) return fail("move", "/dev");
  if (chdir("/root") != 0) return fail("chdir", "/root");
  if (mount(".", "/", NULL, MS_MOVE, NULL) != 0) return fail("move", "/root to /");
  if (chroot(".") != 0 || chdir("/") != 0) return fail("chroot", "/root");
  printf("navd-vm first-boot init: root on /dev/vda, exec %s\n", init);
  fflush(stdout);
  execl(init, init, (char *)NULL);
  return fail("exec", init);
}
