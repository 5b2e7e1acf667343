/*
 * The bus's interfaces as files: $DIR/if/<name> holds "<ifindex> <mtu> <vcan|wire> <up> <txqlen>" (runtime.py
 * writes the first three, and older files have only those: up, qlen 1000). Every process of the bus reads them,
 * so what `ip link set` changes through netlink is seen by all; changes are written under $DIR/.lock (flock, as
 * runtime.py takes it) into a new file renamed over the old one.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>
#include "preload.h"

static int (*links_close)(int);
static int (*links_socket)(int, int, int);
static int (*links_connect)(int, const struct sockaddr *, socklen_t);
static ssize_t (*links_read)(int, void *, size_t);
static ssize_t (*links_write)(int, const void *, size_t);

static void resolve(void)
{
    if (!links_close) {
        links_read = (ssize_t(*)(int, void *, size_t))vc_real("read");
        links_write = (ssize_t(*)(int, const void *, size_t))vc_real("write");
        links_socket = (int (*)(int, int, int))vc_real("socket");
        links_connect = (int (*)(int, const struct sockaddr *, socklen_t))vc_real("connect");
        links_close = (int (*)(int))vc_real("close");
    }
}

int vc_valid_name(const char *name)
{
    size_t len = name ? strnlen(name, IF_NAMESIZE) : 0;
    return len > 0 && len < IF_NAMESIZE && !strchr(name, '/') && name[0] != '.';
}

static int read_file(const char *path, const char *name, struct vc_link *link)
{
    char buf[96], mode[16] = "vcan";
    int idx = 0, m = CANFD_MTU, up = 1;
    unsigned int qlen = VC_DEFAULT_TXQLEN;
    resolve();
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return 0;
    ssize_t n = links_read(fd, buf, sizeof buf - 1);
    links_close(fd);
    if (n <= 0)
        return 0;
    buf[n] = 0;
    if (sscanf(buf, "%d %d %15s %d %u", &idx, &m, mode, &up, &qlen) < 1 || idx <= 0)
        return 0;
    memset(link, 0, sizeof *link);
    memcpy(link->name, name, strlen(name) + 1);
    link->ifindex = idx, link->mtu = m, link->wire = strcmp(mode, "wire") == 0, link->up = up != 0;
    link->txqlen = qlen;
    return 1;
}

int vc_link_by_name(const char *name, struct vc_link *link)
{
    const char *dir = vc_hub_dir();
    char path[4096];
    if (!dir || !vc_valid_name(name))
        return 0;
    if (snprintf(path, sizeof path, "%s/if/%s", dir, name) >= (int)sizeof path)
        return 0;
    return read_file(path, name, link);
}

/* calls found(link, arg) for each interface until it returns non-zero; whether one did */
static int each_link(int (*found)(const struct vc_link *, void *), void *arg)
{
    const char *dir = vc_hub_dir();
    char path[4096];
    int stop = 0;
    if (!dir || snprintf(path, sizeof path, "%s/if", dir) >= (int)sizeof path)
        return 0;
    DIR *d = opendir(path);
    if (!d)
        return 0;
    struct dirent *e;
    while (!stop && (e = readdir(d)) != NULL) {
        struct vc_link link;
        if (vc_valid_name(e->d_name) && vc_link_by_name(e->d_name, &link))
            stop = found(&link, arg);
    }
    closedir(d);
    return stop;
}

struct by_index { int ifindex; struct vc_link *link; };

static int match_index(const struct vc_link *link, void *arg)
{
    struct by_index *want = arg;
    if (link->ifindex != want->ifindex)
        return 0;
    *want->link = *link;
    return 1;
}

int vc_link_by_index(int ifindex, struct vc_link *link)
{
    struct by_index want = {ifindex, link};
    return ifindex > 0 && each_link(match_index, &want);
}

struct collected { struct vc_link *links; int count, max; };

static int collect(const struct vc_link *link, void *arg)
{
    struct collected *c = arg;
    if (c->count < c->max)
        c->links[c->count++] = *link;
    return 0;
}

static int by_ifindex(const void *a, const void *b)
{
    return ((const struct vc_link *)a)->ifindex - ((const struct vc_link *)b)->ifindex;
}

int vc_link_list(struct vc_link *links, int max)
{
    struct collected c = {links, 0, max};
    each_link(collect, &c);
    qsort(links, (size_t)c.count, sizeof *links, by_ifindex);
    return c.count;
}

int vc_links_lock(void)
{
    const char *dir = vc_hub_dir();
    char path[4096];
    resolve();
    if (!dir || snprintf(path, sizeof path, "%s/.lock", dir) >= (int)sizeof path)
        return -1;
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd >= 0 && flock(fd, LOCK_EX) < 0) {
        links_close(fd);
        return -1;
    }
    return fd;
}

void vc_links_unlock(int lock)
{
    resolve();
    if (lock >= 0)
        links_close(lock); /* closing the file releases the flock */
}

int vc_link_store(const struct vc_link *link)
{
    const char *dir = vc_hub_dir();
    char part[4096], path[4096], text[96];
    resolve();
    if (!dir || !vc_valid_name(link->name) ||
        snprintf(part, sizeof part, "%s/if/.%s.part", dir, link->name) >= (int)sizeof part ||
        snprintf(path, sizeof path, "%s/if/%s", dir, link->name) >= (int)sizeof path) {
        errno = ENAMETOOLONG;
        return -1;
    }
    int len = snprintf(text, sizeof text, "%d %d %s %d %u\n", link->ifindex, link->mtu,
                       link->wire ? "wire" : "vcan", link->up ? 1 : 0, link->txqlen);
    int fd = open(part, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        return -1;
    ssize_t n = links_write(fd, text, (size_t)len);
    links_close(fd);
    if (n != len || rename(part, path) < 0) {
        unlink(part);
        if (n != len)
            errno = EIO;
        return -1;
    }
    return 0;
}

/* whether a hub serves the directory: without one the interfaces carry nothing (no carrier) */
int vc_hub_alive(void)
{
    const char *dir = vc_hub_dir();
    struct sockaddr_un sun = {.sun_family = AF_UNIX};
    resolve();
    if (!dir || snprintf(sun.sun_path, sizeof sun.sun_path, "%s/hub.sock", dir) >= (int)sizeof sun.sun_path)
        return 0;
    int fd = links_socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    int alive = fd >= 0 && links_connect(fd, (struct sockaddr *)&sun, sizeof sun) == 0;
    if (fd >= 0)
        links_close(fd);
    return alive;
}
