/*
 * User-space SocketCAN: an LD_PRELOAD library that turns CAN_RAW sockets into connections to a hub
 * process (encoder_conformance/vcan/hub.py), so that unmodified SocketCAN programs (can-utils,
 * CPython's socket module and python-can, CANopenLinux) talk to each other where the kernel has no
 * vcan (containers, CI runners).
 *
 * socket(PF_CAN, SOCK_RAW, CAN_RAW) returns an AF_UNIX SOCK_SEQPACKET socket that this library
 * remembers; bind(sockaddr_can) connects it to $ENCODER_CONFORMANCE_VCAN_DIR/hub.sock and joins the
 * interface. Interfaces are files $DIR/if/<name> (preload_links.c). NETLINK_ROUTE sockets are answered by
 * preload_netlink.c. Every other socket passes through untouched (dlsym(RTLD_NEXT)).
 *
 * Wire protocol (native byte order, kept in step with protocol.py):
 *   to the hub:   a CAN frame (16 bytes) or CAN FD frame (72 bytes) for the bound interface;
 *                 or a control message: struct vc_ctl [+ filters] + 1 pad byte (odd length, never a frame);
 *                 or struct vc_tx + frame + 1 pad byte (sendto() another interface than the bound one).
 *   from the hub: struct vc_rx + frame; struct vc_rx alone with VC_ACK answers VC_JOIN.
 * The receive path reads the header and the frame in one recvmsg() (scatter), so poll/select/epoll
 * on the socket work natively: one readable message is one frame.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <net/if.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/net_tstamp.h>
#include "preload.h"

#define FILTER_MAX 512 /* CAN_RAW_FILTER_MAX */
#define RAW_MIN_NAMELEN 8
#define ACK_TIMEOUT_MS 5000

#define VC_MAGIC 0x4e414356u /* "VCAN" */
#define VC_ACK 0x80000000u
#define VC_OWN 0x1u
enum { VC_JOIN = 1, VC_OPTS = 2, VC_TX = 3 };

struct vc_rx { uint32_t magic, flags; int32_t ifindex; uint32_t drops; int64_t sec, nsec; };
struct vc_ctl {
    uint32_t magic, type;
    int32_t ifindex;
    uint32_t mtu, loopback, recv_own, fd_frames, join_filters, err_mask, rcvbuf, nfilters;
};
struct vc_tx { uint32_t magic, type; int32_t ifindex; };

#ifndef SO_TIMESTAMP_OLD
#define SO_TIMESTAMP_OLD 29
#define SO_TIMESTAMPNS_OLD 35
#define SO_TIMESTAMPING_OLD 37
#endif
#ifndef SO_TIMESTAMP_NEW
#define SO_TIMESTAMP_NEW 63
#define SO_TIMESTAMPNS_NEW 64
#define SO_TIMESTAMPING_NEW 65
#endif
#ifndef SO_RXQ_OVFL
#define SO_RXQ_OVFL 40
#endif
#define STAMP_OLD 0x8906u    /* SIOCGSTAMP_OLD */
#define STAMPNS_OLD 0x8907u  /* SIOCGSTAMPNS_OLD */
#define STAMP_NEW 0x80108906u
#define STAMPNS_NEW 0x80108907u
#define CAN_RAW_XL_OPT 7      /* CAN_RAW_XL_FRAMES: CAN XL is not emulated */
#define CAN_RAW_XL_VCID_OPT 8
#ifndef SOF_TIMESTAMPING_OPT_RX_FILTER
#define SOF_TIMESTAMPING_OPT_RX_FILTER (1 << 17)
#endif
#ifndef CLOSE_RANGE_CLOEXEC
#define CLOSE_RANGE_CLOEXEC (1U << 2)
#endif

enum { TS_NONE, TS_TIMEVAL, TS_TIMESPEC };

struct vstate {
    pthread_mutex_t lock;
    int refs;
    int bound, ifindex, mtu, wire, dead;
    int loopback, recv_own, fd_frames, join_filters;
    uint32_t err_mask;
    int tsmode, ts_new, tsing, tsing_new, rxq_ovfl;
    int rcvbuf;
    struct can_filter *filters;
    int nfilters;
    int have_last;
    int64_t last_sec, last_nsec;
    struct vstate *next_free;
};

static struct vstate *table[MAX_FDS];
static struct vstate *free_states;
static pthread_mutex_t pool_lock = PTHREAD_MUTEX_INITIALIZER;

/* ---- the real functions ---- */
#define REAL(ret, name, ...) static ret (*real_##name)(__VA_ARGS__)
REAL(int, socket, int, int, int);
REAL(int, bind, int, const struct sockaddr *, socklen_t);
REAL(int, connect, int, const struct sockaddr *, socklen_t);
REAL(int, close, int);
REAL(int, dup, int);
REAL(int, dup2, int, int);
REAL(int, dup3, int, int, int);
REAL(int, setsockopt, int, int, int, const void *, socklen_t);
REAL(int, getsockopt, int, int, int, void *, socklen_t *);
REAL(int, getsockname, int, struct sockaddr *, socklen_t *);
REAL(int, getpeername, int, struct sockaddr *, socklen_t *);
REAL(int, ioctl, int, unsigned long, ...);
REAL(unsigned int, if_nametoindex, const char *);
REAL(char *, if_indextoname, unsigned int, char *);
REAL(ssize_t, read, int, void *, size_t);
REAL(ssize_t, readv, int, const struct iovec *, int);
REAL(ssize_t, __read_chk, int, void *, size_t, size_t);
REAL(ssize_t, recv, int, void *, size_t, int);
REAL(ssize_t, __recv_chk, int, void *, size_t, size_t, int);
REAL(ssize_t, recvfrom, int, void *, size_t, int, struct sockaddr *, socklen_t *);
REAL(ssize_t, __recvfrom_chk, int, void *, size_t, size_t, int, struct sockaddr *, socklen_t *);
REAL(ssize_t, recvmsg, int, struct msghdr *, int);
REAL(int, recvmmsg, int, struct mmsghdr *, unsigned int, int, struct timespec *);
REAL(ssize_t, write, int, const void *, size_t);
REAL(ssize_t, writev, int, const struct iovec *, int);
REAL(ssize_t, send, int, const void *, size_t, int);
REAL(ssize_t, sendto, int, const void *, size_t, int, const struct sockaddr *, socklen_t);
REAL(ssize_t, sendmsg, int, const struct msghdr *, int);
REAL(int, sendmmsg, int, struct mmsghdr *, unsigned int, int);
REAL(int, close_range, unsigned int, unsigned int, int);
REAL(int, fcntl, int, int, ...);
REAL(int, fcntl64, int, int, ...);

#define RESOLVE(name)                                                                  \
    do {                                                                               \
        if (__builtin_expect(real_##name == NULL, 0))                                  \
            real_##name = (__typeof__(real_##name))dlsym(RTLD_NEXT, #name);            \
    } while (0)

/* a fork() while another thread holds the pool lock must not leave the child's lock taken */
static void pool_prepare(void) { pthread_mutex_lock(&pool_lock); }
static void pool_resume(void) { pthread_mutex_unlock(&pool_lock); }
/* The process whose table this is. A vfork() child (CPython's subprocess uses vfork) runs in the parent's memory
 * until it execs, and closes every inherited fd on the way: its closes must not empty the parent's table (seen:
 * the tester's CAN socket forgotten after it started a power switch command). fork() children are told apart by
 * the atfork handler, vfork() children by getpid(). */
static pid_t owner_pid;
static void child_resume(void)
{
    owner_pid = getpid();
    pthread_mutex_unlock(&pool_lock);
}
static int in_owner(void) { return getpid() == owner_pid; }
int vc_in_owner(void) { return in_owner(); }
void *vc_real(const char *name) { return dlsym(RTLD_NEXT, name); }
__attribute__((constructor)) static void vcan_init(void)
{
    owner_pid = getpid();
    pthread_atfork(pool_prepare, pool_resume, child_resume);
}

/* ---- per-socket state ---- */
static struct vstate *lookup(int fd)
{
    if (fd < 0 || fd >= MAX_FDS)
        return NULL;
    return __atomic_load_n(&table[fd], __ATOMIC_ACQUIRE);
}

static struct vstate *new_state(void)
{
    struct vstate *st;
    pthread_mutex_lock(&pool_lock);
    st = free_states;
    if (st)
        free_states = st->next_free;
    pthread_mutex_unlock(&pool_lock);
    if (!st) {
        st = calloc(1, sizeof *st); /* states are pooled, never freed: a racing reader never sees freed memory */
        if (!st)
            return NULL;
        pthread_mutex_init(&st->lock, NULL);
    }
    st->refs = 1;
    st->bound = 0, st->ifindex = 0, st->mtu = CANFD_MTU, st->wire = 0, st->dead = 0;
    st->loopback = 1, st->recv_own = 0, st->fd_frames = 0, st->join_filters = 0, st->err_mask = 0;
    st->tsmode = TS_NONE, st->ts_new = 0, st->tsing = 0, st->tsing_new = 0, st->rxq_ovfl = 0;
    st->rcvbuf = 0, st->have_last = 0;
    st->filters = malloc(sizeof(struct can_filter));
    st->nfilters = st->filters ? 1 : 0; /* the kernel's default: one filter passing everything */
    if (st->filters)
        st->filters[0].can_id = 0, st->filters[0].can_mask = 0;
    return st;
}

static void release(struct vstate *st)
{
    int last;
    pthread_mutex_lock(&pool_lock);
    last = --st->refs == 0;
    if (last) {
        free(st->filters);
        st->filters = NULL;
        st->next_free = free_states;
        free_states = st;
    }
    pthread_mutex_unlock(&pool_lock);
}

static void forget(int fd)
{
    if (fd < 0 || fd >= MAX_FDS || !in_owner())
        return;
    vc_nl_forget(fd);
    struct vstate *st = __atomic_exchange_n(&table[fd], NULL, __ATOMIC_ACQ_REL);
    if (st)
        release(st);
}

static void share(int newfd, struct vstate *st)
{
    if (newfd < 0 || newfd >= MAX_FDS || !in_owner())
        return;
    pthread_mutex_lock(&pool_lock);
    st->refs++;
    pthread_mutex_unlock(&pool_lock);
    struct vstate *old = __atomic_exchange_n(&table[newfd], st, __ATOMIC_ACQ_REL);
    if (old)
        release(old);
}

/* ---- interfaces (preload_links.c) ---- */
static const char *hub_dir(void)
{
    const char *dir = getenv(ENV_DIR);
    return dir && *dir ? dir : NULL;
}
const char *vc_hub_dir(void) { return hub_dir(); }

static int if_by_name(const char *name, int *ifindex, int *mtu, int *wire)
{
    struct vc_link link;
    if (!vc_link_by_name(name, &link))
        return 0;
    *ifindex = link.ifindex;
    if (mtu)
        *mtu = link.mtu;
    if (wire)
        *wire = link.wire;
    return 1;
}

static int if_by_index(int ifindex, char *name, int *mtu, int *wire)
{
    struct vc_link link;
    if (!vc_link_by_index(ifindex, &link))
        return 0;
    if (name)
        memcpy(name, link.name, strlen(link.name) + 1);
    if (mtu)
        *mtu = link.mtu;
    if (wire)
        *wire = link.wire;
    return 1;
}

/* ---- talking to the hub ---- */
static int send_all(int fd, const void *buf, size_t len)
{
    RESOLVE(send);
    for (int tries = 0; tries < 50; tries++) {
        ssize_t n = real_send(fd, buf, len, MSG_NOSIGNAL);
        if (n >= 0)
            return 0;
        if (errno == EINTR)
            continue;
        if (errno != EAGAIN)
            return -1;
        struct pollfd p = {fd, POLLOUT, 0};
        poll(&p, 1, 100);
    }
    errno = EAGAIN;
    return -1;
}

/* the socket's options as a control message; called with st->lock held */
static int send_options(int fd, struct vstate *st, uint32_t type)
{
    size_t len = sizeof(struct vc_ctl) + (size_t)st->nfilters * sizeof(struct can_filter) + 1;
    char *buf = calloc(1, len);
    if (!buf) {
        errno = ENOMEM;
        return -1;
    }
    struct vc_ctl c = {VC_MAGIC, type, st->ifindex, (uint32_t)st->mtu, (uint32_t)st->loopback,
                       (uint32_t)st->recv_own, (uint32_t)st->fd_frames, (uint32_t)st->join_filters,
                       st->err_mask, (uint32_t)st->rcvbuf, (uint32_t)st->nfilters};
    memcpy(buf, &c, sizeof c);
    if (st->nfilters)
        memcpy(buf + sizeof c, st->filters, (size_t)st->nfilters * sizeof(struct can_filter));
    int r = send_all(fd, buf, len);
    free(buf);
    return r;
}

static int wait_ack(int fd)
{
    struct vc_rx hdr;
    RESOLVE(recv);
    struct timespec start, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (;;) {
        clock_gettime(CLOCK_MONOTONIC, &now);
        long waited = (now.tv_sec - start.tv_sec) * 1000 + (now.tv_nsec - start.tv_nsec) / 1000000;
        if (waited >= ACK_TIMEOUT_MS) {
            errno = ETIMEDOUT;
            return -1;
        }
        struct pollfd p = {fd, POLLIN, 0};
        int r = poll(&p, 1, (int)(ACK_TIMEOUT_MS - waited));
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            continue;
        ssize_t n = real_recv(fd, &hdr, sizeof hdr, MSG_DONTWAIT);
        if (n < 0 && (errno == EINTR || errno == EAGAIN))
            continue;
        if (n == (ssize_t)sizeof hdr && hdr.magic == VC_MAGIC && (hdr.flags & VC_ACK))
            return 0;
        errno = n == 0 ? ENETDOWN : EPROTO;
        return -1;
    }
}

/* the interface index a CAN address names (as the kernel checks it); -1 with EINVAL for a wrong address */
static int address_ifindex(const struct sockaddr *addr, socklen_t len)
{
    struct sockaddr_can a;
    if (!addr || len < RAW_MIN_NAMELEN) {
        errno = EINVAL;
        return -1;
    }
    memset(&a, 0, sizeof a);
    memcpy(&a, addr, len < sizeof a ? len : sizeof a);
    if (a.can_family != AF_CAN) {
        errno = EINVAL;
        return -1;
    }
    return a.can_ifindex;
}

static int vcan_bind(int fd, struct vstate *st, const struct sockaddr *addr, socklen_t len)
{
    int ifindex, mtu = CANFD_MTU, wire = 0;
    char name[IF_NAMESIZE];
    ifindex = address_ifindex(addr, len);
    if (ifindex < 0)
        return -1;
    if (ifindex != 0 && !if_by_index(ifindex, name, &mtu, &wire)) {
        errno = ENODEV;
        return -1;
    }
    pthread_mutex_lock(&st->lock);
    if (st->bound) { /* bound again: move to the other interface */
        st->ifindex = ifindex, st->mtu = mtu, st->wire = wire;
        int r = send_options(fd, st, VC_OPTS);
        pthread_mutex_unlock(&st->lock);
        return r;
    }
    struct sockaddr_un sun;
    const char *dir = hub_dir();
    memset(&sun, 0, sizeof sun);
    sun.sun_family = AF_UNIX;
    if (!dir || snprintf(sun.sun_path, sizeof sun.sun_path, "%s/hub.sock", dir) >= (int)sizeof sun.sun_path) {
        pthread_mutex_unlock(&st->lock);
        errno = dir ? ENAMETOOLONG : ENETDOWN;
        return -1;
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0 && (flags & O_NONBLOCK))
        fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    int r = connect(fd, (struct sockaddr *)&sun, sizeof sun);
    if (r < 0 && (errno == ENOENT || errno == ECONNREFUSED))
        errno = ENETDOWN; /* no hub: the interface is down */
    if (r == 0) {
        st->ifindex = ifindex, st->mtu = mtu, st->wire = wire;
        r = send_options(fd, st, VC_JOIN);
        if (r == 0)
            r = wait_ack(fd);
        if (r == 0)
            __atomic_store_n(&st->bound, 1, __ATOMIC_RELEASE);
    }
    int saved = errno;
    if (flags >= 0 && (flags & O_NONBLOCK))
        fcntl(fd, F_SETFL, flags);
    pthread_mutex_unlock(&st->lock);
    errno = saved;
    return r;
}

/* The hub went away: the interface is gone. The program is told once (ENETDOWN); then the socket is
 * swapped for one that never becomes readable (its peer stays open, unused), as a kernel socket whose
 * interface was deleted stays quiet: an epoll loop does not spin on a hung-up connection. */
static void go_quiet(int fd, struct vstate *st)
{
    int pair[2];
    RESOLVE(dup3);
    RESOLVE(close);
    pthread_mutex_lock(&st->lock);
    if (!st->dead && socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, pair) == 0) {
        int status = fcntl(fd, F_GETFL), fdflags = fcntl(fd, F_GETFD);
        if (status >= 0)
            fcntl(pair[0], F_SETFL, status);
        real_dup3(pair[0], fd, fdflags >= 0 && (fdflags & FD_CLOEXEC) ? O_CLOEXEC : 0);
        real_close(pair[0]);
    }
    __atomic_store_n(&st->dead, 1, __ATOMIC_RELEASE);
    pthread_mutex_unlock(&st->lock);
}

/* ---- receiving ---- */
/* the kernel's put_cmsg(): a cmsg that does not fit is cut and flagged MSG_CTRUNC */
static void put_cmsg(struct msghdr *um, size_t *used, int level, int type, const void *data, size_t len)
{
    char *base = um->msg_control;
    size_t left = um->msg_controllen > *used ? um->msg_controllen - *used : 0;
    size_t cmlen = CMSG_LEN(len);
    if (!base || left < sizeof(struct cmsghdr)) {
        um->msg_flags |= MSG_CTRUNC;
        return;
    }
    if (left < cmlen) {
        um->msg_flags |= MSG_CTRUNC;
        cmlen = left;
    }
    struct cmsghdr h;
    memset(&h, 0, sizeof h);
    h.cmsg_len = cmlen, h.cmsg_level = level, h.cmsg_type = type;
    memcpy(base + *used, &h, sizeof h);
    memcpy(base + *used + CMSG_LEN(0), data, cmlen - CMSG_LEN(0));
    cmlen = CMSG_SPACE(len);
    *used += cmlen < left ? cmlen : left;
}

static void put_stamps(struct vstate *st, struct msghdr *um, const struct vc_rx *h)
{
    size_t used = 0;
    int tsmode = __atomic_load_n(&st->tsmode, __ATOMIC_RELAXED);
    int tsing = __atomic_load_n(&st->tsing, __ATOMIC_RELAXED);
    if (tsmode == TS_TIMEVAL) {
        int64_t tv[2] = {h->sec, h->nsec / 1000};
        put_cmsg(um, &used, SOL_SOCKET, st->ts_new ? SO_TIMESTAMP_NEW : SO_TIMESTAMP_OLD, tv, sizeof tv);
    } else if (tsmode == TS_TIMESPEC) {
        int64_t ts[2] = {h->sec, h->nsec};
        put_cmsg(um, &used, SOL_SOCKET, st->ts_new ? SO_TIMESTAMPNS_NEW : SO_TIMESTAMPNS_OLD, ts, sizeof ts);
    }
    if ((tsing & SOF_TIMESTAMPING_SOFTWARE) &&
        ((tsing & SOF_TIMESTAMPING_RX_SOFTWARE) || !(tsing & SOF_TIMESTAMPING_OPT_RX_FILTER))) {
        int64_t three[6] = {h->sec, h->nsec, 0, 0, 0, 0}; /* software, (deprecated), hardware */
        put_cmsg(um, &used, SOL_SOCKET, st->tsing_new ? SO_TIMESTAMPING_NEW : SO_TIMESTAMPING_OLD, three,
                 sizeof three);
    }
    if (__atomic_load_n(&st->rxq_ovfl, __ATOMIC_RELAXED) && h->drops) {
        uint32_t drops = h->drops;
        put_cmsg(um, &used, SOL_SOCKET, SO_RXQ_OVFL, &drops, sizeof drops);
    }
    um->msg_controllen = used;
}

static ssize_t vcan_recv(int fd, struct vstate *st, struct msghdr *um, int flags)
{
    struct vc_rx hdr;
    struct iovec stack_iov[17], *iov = stack_iov;
    size_t n = um->msg_iovlen;
    ssize_t r;
    RESOLVE(recvmsg);
    if (n > 16) {
        iov = malloc((n + 1) * sizeof *iov);
        if (!iov) {
            errno = ENOMEM;
            return -1;
        }
    }
    iov[0].iov_base = &hdr, iov[0].iov_len = sizeof hdr;
    if (n)
        memcpy(iov + 1, um->msg_iov, n * sizeof *iov);
    for (;;) {
        struct msghdr m;
        memset(&m, 0, sizeof m);
        m.msg_iov = iov, m.msg_iovlen = n + 1;
        r = real_recvmsg(fd, &m, flags & ~MSG_CMSG_CLOEXEC);
        if (r < 0)
            break;
        if (r == 0) { /* the hub went away: the interface is gone */
            if (!__atomic_load_n(&st->dead, __ATOMIC_ACQUIRE))
                go_quiet(fd, st);
            errno = ENETDOWN;
            r = -1;
            break;
        }
        if (r < (ssize_t)sizeof hdr || hdr.magic != VC_MAGIC) {
            errno = EPROTO;
            r = -1;
            break;
        }
        if (hdr.flags & VC_ACK) { /* cannot come after bind(), but never hand it to the program */
            if (flags & MSG_PEEK)
                real_recvmsg(fd, &m, (flags & ~MSG_PEEK & ~MSG_CMSG_CLOEXEC) | MSG_DONTWAIT);
            continue;
        }
        r -= (ssize_t)sizeof hdr;
        /* vcan: every frame was sent on this host (MSG_DONTROUTE); "wire" interfaces: only our own */
        int own = (hdr.flags & VC_OWN) != 0, local = own || !__atomic_load_n(&st->wire, __ATOMIC_RELAXED);
        um->msg_flags = (m.msg_flags & MSG_TRUNC) | (local ? MSG_DONTROUTE : 0) | (own ? MSG_CONFIRM : 0);
        if (um->msg_name) {
            struct sockaddr_can a;
            memset(&a, 0, sizeof a);
            a.can_family = AF_CAN, a.can_ifindex = hdr.ifindex;
            memcpy(um->msg_name, &a, um->msg_namelen < RAW_MIN_NAMELEN ? um->msg_namelen : RAW_MIN_NAMELEN);
            um->msg_namelen = RAW_MIN_NAMELEN;
        } else {
            um->msg_namelen = 0;
        }
        put_stamps(st, um, &hdr);
        if (!(flags & MSG_PEEK)) {
            st->last_sec = hdr.sec, st->last_nsec = hdr.nsec;
            __atomic_store_n(&st->have_last, 1, __ATOMIC_RELEASE);
        }
        break;
    }
    int saved = errno;
    if (iov != stack_iov)
        free(iov);
    errno = saved;
    return r;
}

static ssize_t recv_plain(int fd, struct vstate *st, void *buf, size_t len, int flags, struct sockaddr *from,
                          socklen_t *fromlen)
{
    struct iovec iov = {buf, len};
    struct msghdr m;
    memset(&m, 0, sizeof m);
    m.msg_iov = &iov, m.msg_iovlen = 1;
    m.msg_name = from, m.msg_namelen = from && fromlen ? *fromlen : 0;
    ssize_t r = vcan_recv(fd, st, &m, flags);
    if (r >= 0 && from && fromlen)
        *fromlen = m.msg_namelen;
    return r;
}

/* ---- sending ---- */
static ssize_t vcan_send(int fd, struct vstate *st, const struct iovec *iov, size_t iovcnt, int flags,
                         const struct sockaddr *addr, socklen_t alen)
{
    size_t len = 0;
    int target;
    RESOLVE(sendmsg);
    for (size_t i = 0; i < iovcnt; i++)
        len += iov[i].iov_len;
    if (addr) {
        target = address_ifindex(addr, alen);
        if (target < 0)
            return -1;
    } else {
        target = __atomic_load_n(&st->ifindex, __ATOMIC_RELAXED);
    }
    if (!__atomic_load_n(&st->bound, __ATOMIC_ACQUIRE)) {
        errno = target ? ENOTCONN : ENXIO; /* the kernel's ENXIO; sendto() from an unbound socket: not emulated */
        return -1;
    }
    if (__atomic_load_n(&st->dead, __ATOMIC_ACQUIRE)) {
        errno = ENETDOWN;
        return -1;
    }
    int mtu = CANFD_MTU;
    if (target == 0 || (target != st->ifindex && !if_by_index(target, NULL, &mtu, NULL))) {
        errno = ENXIO;
        return -1;
    }
    if (target == st->ifindex)
        mtu = st->mtu;
    if (len != CAN_MTU && !(len == CANFD_MTU && st->fd_frames && mtu >= (int)CANFD_MTU)) {
        errno = EINVAL;
        return -1;
    }
    struct msghdr m;
    memset(&m, 0, sizeof m);
    ssize_t r;
    if (target == st->ifindex) {
        m.msg_iov = (struct iovec *)iov, m.msg_iovlen = iovcnt;
        r = real_sendmsg(fd, &m, (flags & (MSG_DONTWAIT)) | MSG_NOSIGNAL);
    } else { /* a frame for another interface than the bound one */
        char buf[sizeof(struct vc_tx) + CANFD_MTU + 1];
        struct vc_tx tx = {VC_MAGIC, VC_TX, target};
        size_t off = sizeof tx;
        memcpy(buf, &tx, sizeof tx);
        for (size_t i = 0; i < iovcnt; i++)
            memcpy(buf + off, iov[i].iov_base, iov[i].iov_len), off += iov[i].iov_len;
        buf[off++] = 0;
        struct iovec one = {buf, off};
        m.msg_iov = &one, m.msg_iovlen = 1;
        r = real_sendmsg(fd, &m, (flags & (MSG_DONTWAIT)) | MSG_NOSIGNAL);
        if (r > 0)
            r = (ssize_t)len;
    }
    if (r < 0 && (errno == EPIPE || errno == ECONNRESET)) {
        go_quiet(fd, st);
        errno = ENETDOWN;
    }
    return r;
}

/* ---- options ---- */
static int int_opt(const void *val, socklen_t len, int *out)
{
    if (len < sizeof(int) || !val) {
        errno = EINVAL;
        return -1;
    }
    memcpy(out, val, sizeof(int));
    return 0;
}

static int can_raw_setsockopt(int fd, struct vstate *st, int opt, const void *val, socklen_t len)
{
    int v = 0, r = 0;
    struct can_filter *filters = NULL;
    switch (opt) {
    case CAN_RAW_FILTER:
        if (len % sizeof(struct can_filter) || len / sizeof(struct can_filter) > FILTER_MAX || (len && !val)) {
            errno = EINVAL;
            return -1;
        }
        if (len && !(filters = malloc(len))) {
            errno = ENOMEM;
            return -1;
        }
        if (len)
            memcpy(filters, val, len);
        break;
    case CAN_RAW_ERR_FILTER:
        if (len != sizeof(can_err_mask_t) || !val) {
            errno = EINVAL;
            return -1;
        }
        memcpy(&v, val, sizeof v);
        break;
    case CAN_RAW_LOOPBACK:
    case CAN_RAW_RECV_OWN_MSGS:
    case CAN_RAW_FD_FRAMES:
    case CAN_RAW_JOIN_FILTERS:
        if (len != sizeof(int)) {
            errno = EINVAL;
            return -1;
        }
        if (int_opt(val, len, &v) < 0)
            return -1;
        break;
    default: /* CAN XL and anything newer are not emulated */
        errno = ENOPROTOOPT;
        return -1;
    }
    pthread_mutex_lock(&st->lock);
    switch (opt) {
    case CAN_RAW_FILTER:
        free(st->filters);
        st->filters = filters, st->nfilters = (int)(len / sizeof(struct can_filter));
        break;
    case CAN_RAW_ERR_FILTER: st->err_mask = (uint32_t)v & CAN_ERR_MASK; break;
    case CAN_RAW_LOOPBACK: st->loopback = v; break;
    case CAN_RAW_RECV_OWN_MSGS: st->recv_own = v; break;
    case CAN_RAW_FD_FRAMES: st->fd_frames = v; break;
    case CAN_RAW_JOIN_FILTERS: st->join_filters = v; break;
    }
    if (st->bound)
        r = send_options(fd, st, VC_OPTS) < 0 && errno != EPIPE && errno != ECONNRESET ? -1 : 0;
    pthread_mutex_unlock(&st->lock);
    return r;
}

static int can_raw_getsockopt(struct vstate *st, int opt, void *val, socklen_t *len)
{
    int v;
    if (!len || (int)*len < 0) {
        errno = EINVAL;
        return -1;
    }
    pthread_mutex_lock(&st->lock);
    switch (opt) {
    case CAN_RAW_FILTER: {
        socklen_t size = (socklen_t)(st->nfilters * (int)sizeof(struct can_filter));
        int r = 0;
        if (*len < size) {
            errno = ERANGE, r = -1;
        } else if (size) {
            memcpy(val, st->filters, size);
        }
        *len = size;
        pthread_mutex_unlock(&st->lock);
        return r;
    }
    case CAN_RAW_ERR_FILTER: v = (int)st->err_mask; break;
    case CAN_RAW_LOOPBACK: v = st->loopback; break;
    case CAN_RAW_RECV_OWN_MSGS: v = st->recv_own; break;
    case CAN_RAW_FD_FRAMES: v = st->fd_frames; break;
    case CAN_RAW_JOIN_FILTERS: v = st->join_filters; break;
    default:
        pthread_mutex_unlock(&st->lock);
        errno = ENOPROTOOPT;
        return -1;
    }
    pthread_mutex_unlock(&st->lock);
    if (*len > sizeof v)
        *len = sizeof v;
    memcpy(val, &v, *len);
    return 0;
}

/* SOL_SOCKET options the shim answers itself (the stamps and drop counts come from the hub) */
static int sol_socket_setsockopt(int fd, struct vstate *st, int opt, const void *val, socklen_t len, int *handled)
{
    int v;
    *handled = 1;
    switch (opt) {
    case SO_TIMESTAMP_OLD:
    case SO_TIMESTAMP_NEW:
    case SO_TIMESTAMPNS_OLD:
    case SO_TIMESTAMPNS_NEW:
        if (int_opt(val, len, &v) < 0)
            return -1;
        st->ts_new = opt == SO_TIMESTAMP_NEW || opt == SO_TIMESTAMPNS_NEW;
        __atomic_store_n(&st->tsmode,
                         !v ? TS_NONE : (opt == SO_TIMESTAMP_OLD || opt == SO_TIMESTAMP_NEW) ? TS_TIMEVAL : TS_TIMESPEC,
                         __ATOMIC_RELAXED);
        return 0;
    case SO_TIMESTAMPING_OLD:
    case SO_TIMESTAMPING_NEW:
        if (int_opt(val, len, &v) < 0)
            return -1;
        st->tsing_new = opt == SO_TIMESTAMPING_NEW;
        __atomic_store_n(&st->tsing, v, __ATOMIC_RELAXED);
        return 0;
    case SO_RXQ_OVFL:
        if (int_opt(val, len, &v) < 0)
            return -1;
        __atomic_store_n(&st->rxq_ovfl, v != 0, __ATOMIC_RELAXED);
        return 0;
    case SO_RCVBUF:
    case SO_RCVBUFFORCE: { /* kept on the real socket (getsockopt reads it back) and sized in the hub */
        int r = real_setsockopt(fd, SOL_SOCKET, opt, val, len), eff = 0;
        socklen_t elen = sizeof eff;
        if (r < 0 || real_getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &eff, &elen) < 0)
            return r;
        pthread_mutex_lock(&st->lock);
        st->rcvbuf = eff;
        if (st->bound)
            send_options(fd, st, VC_OPTS);
        pthread_mutex_unlock(&st->lock);
        return 0;
    }
    }
    *handled = 0;
    return 0;
}

static int sol_socket_getsockopt(struct vstate *st, int opt, void *val, socklen_t *len, int *handled)
{
    int v;
    *handled = 1;
    switch (opt) {
    case SO_TIMESTAMP_OLD:
    case SO_TIMESTAMP_NEW: v = st->tsmode == TS_TIMEVAL && st->ts_new == (opt == SO_TIMESTAMP_NEW); break;
    case SO_TIMESTAMPNS_OLD:
    case SO_TIMESTAMPNS_NEW: v = st->tsmode == TS_TIMESPEC && st->ts_new == (opt == SO_TIMESTAMPNS_NEW); break;
    case SO_TIMESTAMPING_OLD:
    case SO_TIMESTAMPING_NEW: v = st->tsing; break;
    case SO_RXQ_OVFL: v = st->rxq_ovfl; break;
    case SO_DOMAIN: v = AF_CAN; break;
    case SO_TYPE: v = SOCK_RAW; break;
    case SO_PROTOCOL: v = CAN_RAW; break;
    default: *handled = 0; return 0;
    }
    if (!len || (int)*len < 0) {
        errno = EINVAL;
        return -1;
    }
    if (*len > sizeof v)
        *len = sizeof v;
    memcpy(val, &v, *len);
    return 0;
}

/* ==== the intercepted functions ==== */
int socket(int domain, int type, int protocol)
{
    RESOLVE(socket);
    int nl = vc_nl_socket(domain, type, protocol);
    if (nl >= 0) {
        struct vstate *stale = __atomic_exchange_n(&table[nl], NULL, __ATOMIC_ACQ_REL);
        if (stale) /* an fd closed behind our back */
            release(stale);
    }
    if (nl != -2)
        return nl;
    if (domain != PF_CAN || (type & 0xf) != SOCK_RAW || protocol != CAN_RAW || !hub_dir())
        return real_socket(domain, type, protocol);
    int fd = real_socket(AF_UNIX, SOCK_SEQPACKET | (type & (SOCK_NONBLOCK | SOCK_CLOEXEC)), 0);
    if (fd < 0)
        return fd;
    struct vstate *st = fd < MAX_FDS ? new_state() : NULL;
    if (!st) {
        RESOLVE(close);
        real_close(fd);
        errno = fd < MAX_FDS ? ENOMEM : EMFILE;
        return -1;
    }
    struct vstate *old = __atomic_exchange_n(&table[fd], st, __ATOMIC_ACQ_REL);
    if (old) /* an fd closed behind our back (not through close()) */
        release(old);
    vc_nl_forget(fd);
    return fd;
}

int bind(int fd, const struct sockaddr *addr, socklen_t len)
{
    struct vstate *st = lookup(fd);
    RESOLVE(bind);
    if (vc_nl_owns(fd))
        return vc_nl_bind(fd, addr, len);
    return st ? vcan_bind(fd, st, addr, len) : real_bind(fd, addr, len);
}

int connect(int fd, const struct sockaddr *addr, socklen_t len)
{
    RESOLVE(connect);
    return vc_nl_owns(fd) ? vc_nl_connect(fd, addr, len) : real_connect(fd, addr, len);
}

int close(int fd)
{
    RESOLVE(close);
    forget(fd);
    return real_close(fd);
}

int close_range(unsigned int first, unsigned int last, int flags)
{
    RESOLVE(close_range);
    if (!real_close_range) {
        errno = ENOSYS;
        return -1;
    }
    if (!(flags & CLOSE_RANGE_CLOEXEC))
        for (unsigned int fd = first; fd <= last && fd < MAX_FDS; fd++)
            if (__atomic_load_n(&table[fd], __ATOMIC_RELAXED) || vc_nl_owns((int)fd)) /* no write: no copied pages */
                forget((int)fd);
    return real_close_range(first, last, flags);
}

int dup(int fd)
{
    RESOLVE(dup);
    int r = real_dup(fd);
    struct vstate *st = lookup(fd);
    if (r >= 0 && st)
        share(r, st);
    if (r >= 0)
        vc_nl_dup(fd, r);
    return r;
}

int dup2(int fd, int newfd)
{
    RESOLVE(dup2);
    int r = real_dup2(fd, newfd);
    if (r >= 0 && fd != newfd) {
        struct vstate *st = lookup(fd);
        if (st)
            share(newfd, st);
        else
            forget(newfd);
        vc_nl_dup(fd, newfd);
    }
    return r;
}

int dup3(int fd, int newfd, int flags)
{
    RESOLVE(dup3);
    int r = real_dup3(fd, newfd, flags);
    if (r >= 0) {
        struct vstate *st = lookup(fd);
        if (st)
            share(newfd, st);
        else
            forget(newfd);
        vc_nl_dup(fd, newfd);
    }
    return r;
}

/* F_DUPFD and F_DUPFD_CLOEXEC duplicate like dup() (CPython's os.dup and socket.dup use them) */
static int after_fcntl(int fd, int cmd, int r)
{
    if (r >= 0 && (cmd == F_DUPFD || cmd == F_DUPFD_CLOEXEC)) {
        struct vstate *st = lookup(fd);
        if (st)
            share(r, st);
        vc_nl_dup(fd, r);
    }
    return r;
}

int fcntl(int fd, int cmd, ...)
{
    va_list ap;
    va_start(ap, cmd);
    void *arg = va_arg(ap, void *);
    va_end(ap);
    RESOLVE(fcntl);
    return after_fcntl(fd, cmd, real_fcntl(fd, cmd, arg));
}

int fcntl64(int fd, int cmd, ...)
{
    va_list ap;
    va_start(ap, cmd);
    void *arg = va_arg(ap, void *);
    va_end(ap);
    RESOLVE(fcntl64);
    RESOLVE(fcntl);
    if (!real_fcntl64) /* a C library without fcntl64 */
        return after_fcntl(fd, cmd, real_fcntl(fd, cmd, arg));
    return after_fcntl(fd, cmd, real_fcntl64(fd, cmd, arg));
}

int setsockopt(int fd, int level, int opt, const void *val, socklen_t len)
{
    struct vstate *st = lookup(fd);
    int handled = 0, r;
    RESOLVE(setsockopt);
    RESOLVE(getsockopt);
    if (vc_nl_owns(fd) && (r = vc_nl_setsockopt(fd, level, opt, val, len)) != -2)
        return r;
    if (!st)
        return real_setsockopt(fd, level, opt, val, len);
    if (level == SOL_CAN_RAW)
        return can_raw_setsockopt(fd, st, opt, val, len);
    if (level == SOL_SOCKET) {
        r = sol_socket_setsockopt(fd, st, opt, val, len, &handled);
        if (handled)
            return r;
    }
    return real_setsockopt(fd, level, opt, val, len);
}

int getsockopt(int fd, int level, int opt, void *val, socklen_t *len)
{
    struct vstate *st = lookup(fd);
    int handled = 0, r;
    RESOLVE(getsockopt);
    if (vc_nl_owns(fd) && (r = vc_nl_getsockopt(fd, level, opt, val, len)) != -2)
        return r;
    if (!st)
        return real_getsockopt(fd, level, opt, val, len);
    if (level == SOL_CAN_RAW)
        return can_raw_getsockopt(st, opt, val, len);
    if (level == SOL_SOCKET) {
        r = sol_socket_getsockopt(st, opt, val, len, &handled);
        if (handled)
            return r;
    }
    return real_getsockopt(fd, level, opt, val, len);
}

int getsockname(int fd, struct sockaddr *addr, socklen_t *len)
{
    struct vstate *st = lookup(fd);
    RESOLVE(getsockname);
    if (vc_nl_owns(fd))
        return vc_nl_getsockname(fd, addr, len);
    if (!st)
        return real_getsockname(fd, addr, len);
    struct sockaddr_can a;
    memset(&a, 0, sizeof a);
    a.can_family = AF_CAN, a.can_ifindex = __atomic_load_n(&st->ifindex, __ATOMIC_RELAXED);
    if (!len) {
        errno = EFAULT;
        return -1;
    }
    memcpy(addr, &a, *len < RAW_MIN_NAMELEN ? *len : RAW_MIN_NAMELEN);
    *len = RAW_MIN_NAMELEN;
    return 0;
}

int getpeername(int fd, struct sockaddr *addr, socklen_t *len)
{
    RESOLVE(getpeername);
    if (lookup(fd)) {
        errno = EOPNOTSUPP;
        return -1;
    }
    return real_getpeername(fd, addr, len);
}

int ioctl(int fd, unsigned long req, ...)
{
    va_list ap;
    va_start(ap, req);
    void *arg = va_arg(ap, void *);
    va_end(ap);
    RESOLVE(ioctl);
    struct ifreq *ifr = arg;
    struct vc_link link;
    int idx, mtu;
    switch (req) {
    case SIOCGIFINDEX:
        if (ifr && if_by_name(ifr->ifr_name, &idx, NULL, NULL)) {
            ifr->ifr_ifindex = idx;
            return 0;
        }
        break;
    case SIOCGIFNAME:
        if (ifr && if_by_index(ifr->ifr_ifindex, ifr->ifr_name, NULL, NULL))
            return 0;
        break;
    case SIOCGIFMTU:
        if (ifr && if_by_name(ifr->ifr_name, &idx, &mtu, NULL)) {
            ifr->ifr_mtu = mtu;
            return 0;
        }
        break;
    case SIOCGIFFLAGS:
        if (ifr && vc_link_by_name(ifr->ifr_name, &link)) {
            int running = link.up && vc_hub_alive(); /* without a hub: up, no carrier */
            ifr->ifr_flags = (short)(IFF_NOARP | (link.up ? IFF_UP : 0) | (running ? IFF_RUNNING : 0));
            return 0;
        }
        break;
    case SIOCGIFTXQLEN:
        if (ifr && vc_link_by_name(ifr->ifr_name, &link)) {
            ifr->ifr_qlen = (int)link.txqlen;
            return 0;
        }
        break;
    case STAMP_OLD:
    case STAMPNS_OLD:
    case STAMP_NEW:
    case STAMPNS_NEW: {
        struct vstate *st = lookup(fd);
        if (!st)
            break;
        if (!__atomic_load_n(&st->have_last, __ATOMIC_ACQUIRE)) {
            errno = ENOENT;
            return -1;
        }
        int64_t t[2] = {st->last_sec, (req == STAMP_OLD || req == STAMP_NEW) ? st->last_nsec / 1000 : st->last_nsec};
        memcpy(arg, t, sizeof t);
        return 0;
    }
    }
    return real_ioctl(fd, req, arg);
}

unsigned int if_nametoindex(const char *name)
{
    int idx;
    RESOLVE(if_nametoindex);
    if (if_by_name(name, &idx, NULL, NULL))
        return (unsigned int)idx;
    return real_if_nametoindex(name);
}

char *if_indextoname(unsigned int ifindex, char name[IF_NAMESIZE])
{
    RESOLVE(if_indextoname);
    if (name && ifindex <= 0x7fffffffu && if_by_index((int)ifindex, name, NULL, NULL))
        return name;
    return real_if_indextoname(ifindex, name);
}

ssize_t recvmsg(int fd, struct msghdr *msg, int flags)
{
    struct vstate *st = lookup(fd);
    RESOLVE(recvmsg);
    if (!st && vc_nl_owns(fd))
        return vc_nl_recvmsg(fd, msg, flags);
    return st ? vcan_recv(fd, st, msg, flags) : real_recvmsg(fd, msg, flags);
}

ssize_t recvfrom(int fd, void *buf, size_t len, int flags, struct sockaddr *from, socklen_t *fromlen)
{
    struct vstate *st = lookup(fd);
    RESOLVE(recvfrom);
    if (!st && vc_nl_owns(fd))
        return vc_nl_recvfrom(fd, buf, len, flags, from, fromlen);
    return st ? recv_plain(fd, st, buf, len, flags, from, fromlen) : real_recvfrom(fd, buf, len, flags, from, fromlen);
}

ssize_t recv(int fd, void *buf, size_t len, int flags)
{
    struct vstate *st = lookup(fd);
    RESOLVE(recv);
    return st ? recv_plain(fd, st, buf, len, flags, NULL, NULL) : real_recv(fd, buf, len, flags);
}

ssize_t read(int fd, void *buf, size_t len)
{
    struct vstate *st = lookup(fd);
    RESOLVE(read);
    return st ? recv_plain(fd, st, buf, len, 0, NULL, NULL) : real_read(fd, buf, len);
}

ssize_t readv(int fd, const struct iovec *iov, int iovcnt)
{
    struct vstate *st = lookup(fd);
    RESOLVE(readv);
    if (!st)
        return real_readv(fd, iov, iovcnt);
    struct msghdr m;
    memset(&m, 0, sizeof m);
    m.msg_iov = (struct iovec *)iov, m.msg_iovlen = iovcnt < 0 ? 0 : (size_t)iovcnt;
    return vcan_recv(fd, st, &m, 0);
}

ssize_t __read_chk(int fd, void *buf, size_t len, size_t buflen);
ssize_t __read_chk(int fd, void *buf, size_t len, size_t buflen)
{
    struct vstate *st = lookup(fd);
    RESOLVE(__read_chk);
    if (!st || len > buflen)
        return real___read_chk(fd, buf, len, buflen);
    return recv_plain(fd, st, buf, len, 0, NULL, NULL);
}

ssize_t __recv_chk(int fd, void *buf, size_t len, size_t buflen, int flags);
ssize_t __recv_chk(int fd, void *buf, size_t len, size_t buflen, int flags)
{
    struct vstate *st = lookup(fd);
    RESOLVE(__recv_chk);
    if (!st || len > buflen)
        return real___recv_chk(fd, buf, len, buflen, flags);
    return recv_plain(fd, st, buf, len, flags, NULL, NULL);
}

ssize_t __recvfrom_chk(int fd, void *buf, size_t len, size_t buflen, int flags, struct sockaddr *from,
                       socklen_t *fromlen);
ssize_t __recvfrom_chk(int fd, void *buf, size_t len, size_t buflen, int flags, struct sockaddr *from,
                       socklen_t *fromlen)
{
    struct vstate *st = lookup(fd);
    RESOLVE(__recvfrom_chk);
    if (!st && vc_nl_owns(fd) && len <= buflen)
        return vc_nl_recvfrom(fd, buf, len, flags, from, fromlen);
    if (!st || len > buflen)
        return real___recvfrom_chk(fd, buf, len, buflen, flags, from, fromlen);
    return recv_plain(fd, st, buf, len, flags, from, fromlen);
}

int recvmmsg(int fd, struct mmsghdr *vec, unsigned int vlen, int flags, struct timespec *timeout)
{
    struct vstate *st = lookup(fd);
    RESOLVE(recvmmsg);
    if (!st)
        return real_recvmmsg(fd, vec, vlen, flags, timeout);
    unsigned int i; /* the time-out is not emulated: MSG_WAITFORONE and MSG_DONTWAIT are */
    for (i = 0; i < vlen; i++) {
        int f = flags & ~MSG_WAITFORONE;
        if (i > 0 && (flags & MSG_WAITFORONE))
            f |= MSG_DONTWAIT;
        ssize_t r = vcan_recv(fd, st, &vec[i].msg_hdr, f);
        if (r < 0)
            return i ? (int)i : -1;
        vec[i].msg_len = (unsigned int)r;
    }
    return (int)i;
}

ssize_t write(int fd, const void *buf, size_t len)
{
    struct vstate *st = lookup(fd);
    RESOLVE(write);
    struct iovec iov = {(void *)buf, len};
    if (!st && vc_nl_owns(fd))
        return vc_nl_send(fd, &iov, 1);
    if (!st)
        return real_write(fd, buf, len);
    return vcan_send(fd, st, &iov, 1, 0, NULL, 0);
}

ssize_t writev(int fd, const struct iovec *iov, int iovcnt)
{
    struct vstate *st = lookup(fd);
    RESOLVE(writev);
    if (!st && vc_nl_owns(fd))
        return vc_nl_send(fd, iov, iovcnt < 0 ? 0 : (size_t)iovcnt);
    if (!st)
        return real_writev(fd, iov, iovcnt);
    return vcan_send(fd, st, iov, iovcnt < 0 ? 0 : (size_t)iovcnt, 0, NULL, 0);
}

ssize_t send(int fd, const void *buf, size_t len, int flags)
{
    struct vstate *st = lookup(fd);
    RESOLVE(send);
    struct iovec iov = {(void *)buf, len};
    if (!st && vc_nl_owns(fd))
        return vc_nl_send(fd, &iov, 1);
    if (!st)
        return real_send(fd, buf, len, flags);
    return vcan_send(fd, st, &iov, 1, flags, NULL, 0);
}

ssize_t sendto(int fd, const void *buf, size_t len, int flags, const struct sockaddr *addr, socklen_t alen)
{
    struct vstate *st = lookup(fd);
    RESOLVE(sendto);
    struct iovec iov = {(void *)buf, len};
    if (!st && vc_nl_owns(fd))
        return vc_nl_send(fd, &iov, 1); /* to the kernel, whatever the address says */
    if (!st)
        return real_sendto(fd, buf, len, flags, addr, alen);
    return vcan_send(fd, st, &iov, 1, flags, addr, alen);
}

ssize_t sendmsg(int fd, const struct msghdr *msg, int flags)
{
    struct vstate *st = lookup(fd);
    RESOLVE(sendmsg);
    if (!st && vc_nl_owns(fd))
        return vc_nl_send(fd, msg->msg_iov, msg->msg_iovlen);
    if (!st)
        return real_sendmsg(fd, msg, flags);
    return vcan_send(fd, st, msg->msg_iov, msg->msg_iovlen, flags, msg->msg_name, msg->msg_namelen);
}

int sendmmsg(int fd, struct mmsghdr *vec, unsigned int vlen, int flags)
{
    struct vstate *st = lookup(fd);
    RESOLVE(sendmmsg);
    if (!st)
        return real_sendmmsg(fd, vec, vlen, flags);
    unsigned int i;
    for (i = 0; i < vlen; i++) {
        ssize_t r = vcan_send(fd, st, vec[i].msg_hdr.msg_iov, vec[i].msg_hdr.msg_iovlen, flags,
                              vec[i].msg_hdr.msg_name, vec[i].msg_hdr.msg_namelen);
        if (r < 0)
            return i ? (int)i : -1;
        vec[i].msg_len = (unsigned int)r;
    }
    return (int)i;
}
