/*
 * rtnetlink for the bus's interfaces: what `ip link`, libsocketcan and CAN stacks ask when they open one.
 *
 * socket(AF_NETLINK, SOCK_RAW|SOCK_DGRAM, NETLINK_ROUTE) under the bus gives an AF_UNIX datagram socket bound
 * to an abstract address of its own; every request sent on it is answered at once by datagrams sent to that
 * address, so read/recv/poll/select/epoll work natively. Answered: RTM_GETLINK (a dump, or one interface by
 * ifi_index or IFLA_IFNAME) with RTM_NEWLINK as the kernel fills it for a vcan; RTM_NEWLINK/RTM_SETLINK changing
 * what a vcan lets change (up/down, txqueuelen, mtu 16/72 while down), the rest refused with the kernel's error;
 * dumps of other kinds (addresses, routes, ...) empty; anything else EOPNOTSUPP. Acks as the kernel gives them.
 * Other netlink families and every other socket pass through to the C library untouched.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <linux/can.h>
#include <linux/if_link.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if_arp.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/un.h>
#include <unistd.h>
#include "preload.h"

#ifndef IFF_LOWER_UP
#define IFF_LOWER_UP 0x10000
#endif
#ifndef ARPHRD_CAN
#define ARPHRD_CAN 280
#endif
#define OPER_UNKNOWN 0 /* IF_OPER_UNKNOWN, IF_OPER_DOWN (linux/if.h clashes with net/if.h) */
#define OPER_DOWN 2
#define CHUNK 4096      /* a dump's datagrams stay this small, as the kernel's skbs for a small reader */
#define MAX_REQUEST 65536
#define LINKS_MAX 256

struct nlsock {
    int refs;
    int type;         /* SOCK_RAW or SOCK_DGRAM, as asked */
    uint32_t portid;  /* 0 until bound (bind, or the first send) */
    int cap_ack;      /* NETLINK_CAP_ACK: errors do not echo the request */
    struct sockaddr_un self;
    socklen_t self_len;
};

static struct nlsock *nl_table[MAX_FDS];
static pthread_mutex_t nl_lock = PTHREAD_MUTEX_INITIALIZER;
static int32_t next_portid = -4096; /* the kernel's autobind numbers after the process's pid */

static int (*r_socket)(int, int, int);
static int (*r_bind)(int, const struct sockaddr *, socklen_t);
static int (*r_close)(int);
static int (*r_getsockname)(int, struct sockaddr *, socklen_t *);
static ssize_t (*r_sendto)(int, const void *, size_t, int, const struct sockaddr *, socklen_t);
static ssize_t (*r_recvmsg)(int, struct msghdr *, int);

static void resolve(void)
{
    if (!r_recvmsg) {
        r_socket = (int (*)(int, int, int))vc_real("socket");
        r_bind = (int (*)(int, const struct sockaddr *, socklen_t))vc_real("bind");
        r_close = (int (*)(int))vc_real("close");
        r_getsockname = (int (*)(int, struct sockaddr *, socklen_t *))vc_real("getsockname");
        r_sendto = (ssize_t(*)(int, const void *, size_t, int, const struct sockaddr *, socklen_t))vc_real("sendto");
        r_recvmsg = (ssize_t(*)(int, struct msghdr *, int))vc_real("recvmsg");
    }
}

static struct nlsock *nl_lookup(int fd)
{
    return fd >= 0 && fd < MAX_FDS ? __atomic_load_n(&nl_table[fd], __ATOMIC_ACQUIRE) : NULL;
}

int vc_nl_owns(int fd) { return nl_lookup(fd) != NULL; }

static void nl_release(struct nlsock *s)
{
    pthread_mutex_lock(&nl_lock);
    int last = --s->refs == 0;
    pthread_mutex_unlock(&nl_lock);
    if (last)
        free(s);
}

static void nl_put(int fd, struct nlsock *s)
{
    if (s) {
        pthread_mutex_lock(&nl_lock);
        s->refs++;
        pthread_mutex_unlock(&nl_lock);
    }
    struct nlsock *old = __atomic_exchange_n(&nl_table[fd], s, __ATOMIC_ACQ_REL);
    if (old)
        nl_release(old);
}

void vc_nl_forget(int fd)
{
    if (fd >= 0 && fd < MAX_FDS && vc_in_owner() && nl_lookup(fd))
        nl_put(fd, NULL);
}

void vc_nl_dup(int fd, int newfd)
{
    if (newfd < 0 || newfd >= MAX_FDS || fd == newfd || !vc_in_owner())
        return;
    struct nlsock *s = nl_lookup(fd);
    if (s || nl_lookup(newfd))
        nl_put(newfd, s);
}

int vc_nl_socket(int domain, int type, int protocol)
{
    int kind = type & 0xf;
    if (domain != AF_NETLINK || protocol != NETLINK_ROUTE || (kind != SOCK_RAW && kind != SOCK_DGRAM) ||
        !vc_hub_dir())
        return -2;
    resolve();
    int fd = r_socket(AF_UNIX, SOCK_DGRAM | (type & (SOCK_NONBLOCK | SOCK_CLOEXEC)), 0);
    if (fd < 0)
        return -1;
    struct nlsock *s = calloc(1, sizeof *s);
    struct sockaddr_un any = {.sun_family = AF_UNIX};
    s = fd < MAX_FDS ? s : (free(s), NULL);
    if (s) { /* autobind: the kernel picks an abstract address the answers are sent to */
        s->self_len = sizeof s->self;
        if (r_bind(fd, (struct sockaddr *)&any, sizeof(sa_family_t)) < 0 ||
            r_getsockname(fd, (struct sockaddr *)&s->self, &s->self_len) < 0) {
            free(s);
            s = NULL;
        }
    }
    if (!s) {
        int saved = fd < MAX_FDS ? errno : EMFILE;
        r_close(fd);
        errno = saved;
        return -1;
    }
    s->type = kind;
    nl_put(fd, s); /* the table holds the only reference */
    return fd;
}

static uint32_t assign_portid(struct nlsock *s)
{
    pthread_mutex_lock(&nl_lock);
    if (!s->portid) {
        static int pid_taken;
        s->portid = pid_taken ? (uint32_t)next_portid-- : (uint32_t)getpid();
        pid_taken = 1;
    }
    pthread_mutex_unlock(&nl_lock);
    return s->portid;
}

int vc_nl_bind(int fd, const struct sockaddr *addr, socklen_t len)
{
    struct nlsock *s = nl_lookup(fd);
    const struct sockaddr_nl *nl = (const struct sockaddr_nl *)addr;
    if (!addr || len < sizeof(struct sockaddr_nl) || nl->nl_family != AF_NETLINK) {
        errno = EINVAL;
        return -1;
    }
    if (nl->nl_pid) { /* multicast groups are accepted: no notifications are sent */
        pthread_mutex_lock(&nl_lock);
        if (!s->portid)
            s->portid = nl->nl_pid;
        pthread_mutex_unlock(&nl_lock);
    }
    assign_portid(s);
    return 0;
}

int vc_nl_connect(int fd, const struct sockaddr *addr, socklen_t len)
{
    const struct sockaddr_nl *nl = (const struct sockaddr_nl *)addr;
    if (!addr || len < sizeof(struct sockaddr_nl) || nl->nl_family != AF_NETLINK) {
        errno = EINVAL;
        return -1;
    }
    assign_portid(nl_lookup(fd));
    return 0;
}

int vc_nl_getsockname(int fd, struct sockaddr *addr, socklen_t *len)
{
    struct nlsock *s = nl_lookup(fd);
    struct sockaddr_nl nl = {.nl_family = AF_NETLINK};
    if (!len || !addr) {
        errno = EFAULT;
        return -1;
    }
    nl.nl_pid = __atomic_load_n(&s->portid, __ATOMIC_RELAXED);
    memcpy(addr, &nl, *len < sizeof nl ? *len : sizeof nl);
    *len = sizeof nl;
    return 0;
}

int vc_nl_setsockopt(int fd, int level, int opt, const void *val, socklen_t len)
{
    struct nlsock *s = nl_lookup(fd);
    int v = 0;
    if (level != SOL_NETLINK)
        return -2;
    if (!val || len < sizeof(int)) {
        errno = EINVAL;
        return -1;
    }
    memcpy(&v, val, sizeof v);
    if (opt == NETLINK_CAP_ACK)
        s->cap_ack = v != 0;
    return 0; /* memberships, extended acks, strict checks: accepted */
}

int vc_nl_getsockopt(int fd, int level, int opt, void *val, socklen_t *len)
{
    struct nlsock *s = nl_lookup(fd);
    int v;
    if (level == SOL_SOCKET && (opt == SO_DOMAIN || opt == SO_PROTOCOL || opt == SO_TYPE))
        v = opt == SO_DOMAIN ? AF_NETLINK : opt == SO_PROTOCOL ? NETLINK_ROUTE : s->type;
    else if (level == SOL_NETLINK)
        v = opt == NETLINK_CAP_ACK ? s->cap_ack : 0;
    else
        return -2;
    if (!val || !len) {
        errno = EFAULT;
        return -1;
    }
    if (*len > sizeof v)
        *len = sizeof v;
    memcpy(val, &v, *len);
    return 0;
}

/* ---- building answers ---- */
struct reply {
    struct nlsock *sock;
    char buf[CHUNK];
    size_t used;
    int failed;
};

static void flush(struct reply *r)
{
    if (!r->used)
        return;
    int out = r_socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (out < 0 || r_sendto(out, r->buf, r->used, MSG_DONTWAIT | MSG_NOSIGNAL, (struct sockaddr *)&r->sock->self,
                            r->sock->self_len) < 0)
        r->failed = 1; /* a reader that lets its queue fill loses answers, as netlink drops them (ENOBUFS) */
    if (out >= 0)
        r_close(out);
    r->used = 0;
}

/* room for a message of len bytes (a new datagram if this one is full); NULL if it can never fit */
static char *room(struct reply *r, size_t len)
{
    len = NLMSG_ALIGN(len);
    if (len > sizeof r->buf)
        return NULL;
    if (r->used + len > sizeof r->buf)
        flush(r);
    char *at = r->buf + r->used;
    memset(at, 0, len);
    r->used += len;
    return at;
}

static struct nlmsghdr *begin(struct reply *r, const struct nlmsghdr *req, int type, int flags, size_t max)
{
    struct nlmsghdr *h = (struct nlmsghdr *)room(r, max);
    if (h) {
        h->nlmsg_len = NLMSG_HDRLEN, h->nlmsg_type = (uint16_t)type, h->nlmsg_flags = (uint16_t)flags;
        h->nlmsg_seq = req->nlmsg_seq, h->nlmsg_pid = r->sock->portid;
    }
    return h;
}

/* the unused tail of the last message given back */
static void finish(struct reply *r, const struct nlmsghdr *h, size_t max)
{
    r->used -= NLMSG_ALIGN(max) - NLMSG_ALIGN(h->nlmsg_len);
}

static struct rtattr *put(struct nlmsghdr *h, int type, const void *data, size_t len)
{
    struct rtattr *a = (struct rtattr *)((char *)h + NLMSG_ALIGN(h->nlmsg_len));
    a->rta_type = (unsigned short)type, a->rta_len = (unsigned short)RTA_LENGTH(len);
    if (len)
        memcpy(RTA_DATA(a), data, len);
    h->nlmsg_len = NLMSG_ALIGN(h->nlmsg_len) + RTA_ALIGN(a->rta_len);
    return a;
}

static void put_u32(struct nlmsghdr *h, int type, uint32_t v) { put(h, type, &v, sizeof v); }
static void put_u8(struct nlmsghdr *h, int type, uint8_t v) { put(h, type, &v, sizeof v); }
static void put_str(struct nlmsghdr *h, int type, const char *s) { put(h, type, s, strlen(s) + 1); }

static void end_nest(struct nlmsghdr *h, struct rtattr *nest)
{
    nest->rta_len = (unsigned short)((char *)h + h->nlmsg_len - (char *)nest);
}

/* IFLA_LINKINFO: the interface's kind. The seam for the "can" kind, which would add IFLA_INFO_DATA with
 * IFLA_CAN_BITTIMING, IFLA_CAN_STATE ... here (a later issue). */
static void put_linkinfo(struct nlmsghdr *h, const struct vc_link *link)
{
    (void)link;
    struct rtattr *info = put(h, IFLA_LINKINFO, NULL, 0);
    put_str(h, IFLA_INFO_KIND, "vcan");
    end_nest(h, info);
}

/* RTM_NEWLINK for one interface, filled as the kernel's rtnl_fill_ifinfo fills it for a vcan. Without a hub
 * (``carrier`` 0) an interface that is up carries nothing: reported as a link without carrier (NO-CARRIER). */
static void put_link(struct reply *r, const struct nlmsghdr *req, const struct vc_link *link, int flags, int carrier)
{
    size_t max = 512;
    struct nlmsghdr *h = begin(r, req, RTM_NEWLINK, flags, max);
    struct ifinfomsg *ifi = NLMSG_DATA(h);
    h->nlmsg_len = NLMSG_LENGTH(sizeof *ifi);
    ifi->ifi_family = AF_UNSPEC, ifi->ifi_type = ARPHRD_CAN, ifi->ifi_index = link->ifindex;
    ifi->ifi_flags = IFF_NOARP | (link->up ? IFF_UP : 0) | (link->up && carrier ? IFF_RUNNING | IFF_LOWER_UP : 0);
    put_str(h, IFLA_IFNAME, link->name);
    put_u32(h, IFLA_TXQLEN, link->txqlen);
    put_u8(h, IFLA_OPERSTATE, link->up && carrier ? OPER_UNKNOWN : OPER_DOWN); /* a vcan: UNKNOWN when up */
    put_u8(h, IFLA_LINKMODE, 0);
    put_u32(h, IFLA_MTU, (uint32_t)link->mtu);
    put_u32(h, IFLA_MIN_MTU, 0);
    put_u32(h, IFLA_MAX_MTU, 0);
    put_u32(h, IFLA_GROUP, 0);
    put_u32(h, IFLA_PROMISCUITY, 0);
    put_u32(h, IFLA_NUM_TX_QUEUES, 1);
    put_u32(h, IFLA_NUM_RX_QUEUES, 1);
    put_u8(h, IFLA_CARRIER, (uint8_t)(carrier != 0));
    put_str(h, IFLA_QDISC, link->up ? "noqueue" : "noop");
    put_u8(h, IFLA_PROTO_DOWN, 0);
    put_linkinfo(h, link);
    finish(r, h, max);
}

/* NLMSG_ERROR: error 0 is an ack (the request's header only); an error echoes the request unless NETLINK_CAP_ACK */
static void put_error(struct reply *r, const struct nlmsghdr *req, int error)
{
    int echo = error && !r->sock->cap_ack;
    size_t max = NLMSG_LENGTH(sizeof(struct nlmsgerr)) + (echo ? NLMSG_ALIGN(req->nlmsg_len) - NLMSG_HDRLEN : 0);
    if (max > CHUNK)
        echo = 0, max = NLMSG_LENGTH(sizeof(struct nlmsgerr));
    struct nlmsghdr *h = begin(r, req, NLMSG_ERROR, echo ? 0 : NLM_F_CAPPED, max);
    struct nlmsgerr *e = NLMSG_DATA(h);
    e->error = error;
    memcpy(&e->msg, req, echo ? req->nlmsg_len : NLMSG_HDRLEN);
    h->nlmsg_len = (uint32_t)max;
}

static void put_done(struct reply *r, const struct nlmsghdr *req)
{
    struct nlmsghdr *h = begin(r, req, NLMSG_DONE, NLM_F_MULTI, NLMSG_LENGTH(sizeof(int)));
    h->nlmsg_len = NLMSG_LENGTH(sizeof(int)); /* the dump's status: 0 */
}

/* ---- requests ---- */
struct attrs { const struct rtattr *at[IFLA_MAX + 1]; };

static void parse_attrs(const struct nlmsghdr *req, size_t head, struct attrs *out)
{
    memset(out, 0, sizeof *out);
    if (req->nlmsg_len < NLMSG_LENGTH(head))
        return;
    int left = (int)(req->nlmsg_len - NLMSG_LENGTH(head));
    for (const struct rtattr *a = (const struct rtattr *)((const char *)NLMSG_DATA(req) + NLMSG_ALIGN(head));
         RTA_OK(a, left); a = RTA_NEXT(a, left))
        if ((a->rta_type & NLA_TYPE_MASK) <= IFLA_MAX)
            out->at[a->rta_type & NLA_TYPE_MASK] = a;
}

static int attr_u32(const struct rtattr *a, uint32_t *v)
{
    if (RTA_PAYLOAD(a) < sizeof *v)
        return 0;
    memcpy(v, RTA_DATA(a), sizeof *v);
    return 1;
}

static int attr_name(const struct rtattr *a, char name[IF_NAMESIZE])
{
    size_t len = strnlen(RTA_DATA(a), RTA_PAYLOAD(a));
    if (!len || len >= IF_NAMESIZE)
        return 0;
    memcpy(name, RTA_DATA(a), len);
    name[len] = 0;
    return 1;
}

/* the interface a request names by ifi_index, else IFLA_IFNAME: 1 found, 0 not found, -EINVAL neither */
static int named_link(const struct ifinfomsg *ifi, const struct attrs *t, struct vc_link *link)
{
    char name[IF_NAMESIZE];
    if (ifi && ifi->ifi_index > 0)
        return vc_link_by_index(ifi->ifi_index, link);
    if (t->at[IFLA_IFNAME])
        return attr_name(t->at[IFLA_IFNAME], name) && vc_link_by_name(name, link);
    return -EINVAL;
}

/* the kind a request names in IFLA_LINKINFO ("" if none); whether it carries IFLA_INFO_DATA */
static int linkinfo_kind(const struct attrs *t, char kind[32])
{
    int data = 0;
    kind[0] = 0;
    if (!t->at[IFLA_LINKINFO])
        return 0;
    int left = (int)RTA_PAYLOAD(t->at[IFLA_LINKINFO]);
    for (const struct rtattr *a = RTA_DATA(t->at[IFLA_LINKINFO]); RTA_OK(a, left); a = RTA_NEXT(a, left)) {
        if ((a->rta_type & NLA_TYPE_MASK) == IFLA_INFO_KIND) {
            size_t len = strnlen(RTA_DATA(a), RTA_PAYLOAD(a));
            len = len < 31 ? len : 31;
            memcpy(kind, RTA_DATA(a), len);
            kind[len] = 0;
        }
        data |= (a->rta_type & NLA_TYPE_MASK) == IFLA_INFO_DATA;
    }
    return data;
}

static int get_link(struct reply *r, const struct nlmsghdr *req)
{
    const struct ifinfomsg *ifi = req->nlmsg_len >= NLMSG_LENGTH(sizeof *ifi) ? NLMSG_DATA(req) : NULL;
    struct attrs t;
    struct vc_link link;
    char kind[32];
    parse_attrs(req, ifi ? sizeof *ifi : 0, &t);
    if (req->nlmsg_flags & NLM_F_DUMP) {
        static struct vc_link links[LINKS_MAX];
        static pthread_mutex_t dump_lock = PTHREAD_MUTEX_INITIALIZER;
        linkinfo_kind(&t, kind); /* a dump filtered by kind (`ip link show type can`) */
        pthread_mutex_lock(&dump_lock);
        int n = kind[0] && strcmp(kind, "vcan") ? 0 : vc_link_list(links, LINKS_MAX);
        int carrier = n ? vc_hub_alive() : 0;
        for (int i = 0; i < n; i++)
            put_link(r, req, &links[i], NLM_F_MULTI, carrier);
        pthread_mutex_unlock(&dump_lock);
        put_done(r, req);
        return 1; /* a dump is not acked */
    }
    int found = named_link(ifi, &t, &link);
    if (found <= 0)
        return found < 0 ? found : -ENODEV;
    put_link(r, req, &link, 0, vc_hub_alive());
    return 0;
}

/* a change of kind-specific settings (IFLA_INFO_DATA). The seam for the "can" kind's bit rate (later): a vcan
 * has no changelink, so the kernel refuses any, of its own kind or another. */
static int change_kind(const struct vc_link *link, const char *kind)
{
    (void)link, (void)kind;
    return -EOPNOTSUPP;
}

/* RTM_NEWLINK / RTM_SETLINK on an interface: validated whole, then stored (the kernel applies in this order) */
static int set_link(const struct nlmsghdr *req)
{
    const struct ifinfomsg *ifi = req->nlmsg_len >= NLMSG_LENGTH(sizeof *ifi) ? NLMSG_DATA(req) : NULL;
    struct attrs t;
    struct vc_link link, now;
    char kind[32], name[IF_NAMESIZE];
    if (!ifi)
        return -EINVAL;
    parse_attrs(req, sizeof *ifi, &t);
    int lock = vc_links_lock();
    int found = named_link(ifi, &t, &link), err = 0;
    if (found <= 0) /* a new interface: `vcan up` makes them, not netlink */
        err = found < 0 || !(req->nlmsg_flags & NLM_F_CREATE) ? -ENODEV : -EOPNOTSUPP;
    else if ((req->nlmsg_flags & NLM_F_CREATE) && (req->nlmsg_flags & NLM_F_EXCL))
        err = -EEXIST;
    now = link;
    if (!err && linkinfo_kind(&t, kind))
        err = change_kind(&link, kind);
    for (int type = 1; !err && type <= IFLA_MAX; type++) {
        const struct rtattr *a = t.at[type];
        uint32_t v = 0;
        if (!a)
            continue;
        switch (type) {
        case IFLA_IFNAME: /* a rename: refused while up as the kernel does; not emulated while down */
            if (!attr_name(a, name))
                err = -EINVAL;
            else if (strcmp(name, link.name))
                err = link.up ? -EBUSY : -EOPNOTSUPP;
            break;
        case IFLA_ADDRESS: err = -EOPNOTSUPP; break; /* vcan has no ndo_set_mac_address */
        case IFLA_MTU:
            if (!attr_u32(a, &v))
                err = -EINVAL;
            else if ((int)v != link.mtu)
                err = link.up ? -EBUSY : (v == CAN_MTU || v == CANFD_MTU) ? (now.mtu = (int)v, 0) : -EINVAL;
            break;
        case IFLA_TXQLEN:
            if (!attr_u32(a, &v))
                err = -EINVAL;
            else
                now.txqlen = v;
            break;
        case IFLA_LINKINFO: case IFLA_BROADCAST: case IFLA_GROUP: case IFLA_OPERSTATE: case IFLA_LINKMODE:
        case IFLA_EXT_MASK: case IFLA_PROMISCUITY:
            break; /* a vcan takes these without effect here */
        default: err = -EOPNOTSUPP; /* (alias, namespaces, VFs, XDP, ...): not emulated */
        }
    }
    if (!err && (ifi->ifi_change & IFF_UP))
        now.up = (ifi->ifi_flags & IFF_UP) != 0;
    else if (!err && !ifi->ifi_change && ifi->ifi_flags)
        now.up = (ifi->ifi_flags & IFF_UP) != 0; /* the old interface: ifi_flags are the new flags */
    if (!err && memcmp(&now, &link, sizeof now) && vc_link_store(&now) < 0)
        err = -errno;
    vc_links_unlock(lock);
    return err;
}

/* one request; its answer goes into r. Returns the error for NLMSG_ERROR, or 1 when nothing more is sent. */
static int handle(struct reply *r, const struct nlmsghdr *req)
{
    int type = req->nlmsg_type;
    if (type < NLMSG_MIN_TYPE)
        return 0; /* NOOP and friends: acked if asked */
    switch (type) {
    case RTM_GETLINK: return get_link(r, req);
    case RTM_NEWLINK:
    case RTM_SETLINK: return set_link(req);
    }
    if (type % 4 == 2 && (req->nlmsg_flags & NLM_F_DUMP)) { /* RTM_GETADDR, RTM_GETROUTE, ...: none here */
        put_done(r, req);
        return 1;
    }
    return -EOPNOTSUPP;
}

ssize_t vc_nl_send(int fd, const struct iovec *iov, size_t iovcnt)
{
    struct nlsock *s = nl_lookup(fd);
    size_t total = 0;
    resolve();
    for (size_t i = 0; i < iovcnt; i++)
        total += iov[i].iov_len;
    if (total > MAX_REQUEST) {
        errno = EMSGSIZE;
        return -1;
    }
    struct reply *r = malloc(sizeof *r);
    char *buf = malloc(total ? total : 1);
    if (!r || !buf) {
        free(r), free(buf);
        errno = ENOBUFS;
        return -1;
    }
    for (size_t i = 0, at = 0; i < iovcnt; at += iov[i].iov_len, i++)
        memcpy(buf + at, iov[i].iov_base, iov[i].iov_len);
    r->sock = s, r->used = 0, r->failed = 0;
    assign_portid(s);
    size_t left = total;
    for (const struct nlmsghdr *req = (const struct nlmsghdr *)buf; NLMSG_OK(req, left); req = NLMSG_NEXT(req, left)) {
        if (!(req->nlmsg_flags & NLM_F_REQUEST))
            continue; /* the kernel takes requests only */
        int err = handle(r, req);
        if (err != 1 && (err || (req->nlmsg_flags & NLM_F_ACK)))
            put_error(r, req, err);
    }
    flush(r);
    free(r), free(buf);
    return (ssize_t)total;
}

ssize_t vc_nl_recvmsg(int fd, struct msghdr *msg, int flags)
{
    void *name = msg->msg_name;
    socklen_t namelen = msg->msg_namelen;
    size_t room_left = 0;
    resolve();
    for (size_t i = 0; i < msg->msg_iovlen; i++)
        room_left += msg->msg_iov[i].iov_len;
    msg->msg_name = NULL, msg->msg_namelen = 0;
    ssize_t n = r_recvmsg(fd, msg, flags | MSG_TRUNC);
    msg->msg_name = name;
    if (n < 0) {
        msg->msg_namelen = namelen;
        return n;
    }
    if ((size_t)n > room_left)
        msg->msg_flags |= MSG_TRUNC;
    if (name) { /* from the kernel: port 0 */
        struct sockaddr_nl from = {.nl_family = AF_NETLINK};
        memcpy(name, &from, namelen < sizeof from ? namelen : sizeof from);
    }
    msg->msg_namelen = name ? sizeof(struct sockaddr_nl) : 0;
    return (flags & MSG_TRUNC) || (size_t)n <= room_left ? n : (ssize_t)room_left;
}

ssize_t vc_nl_recvfrom(int fd, void *buf, size_t len, int flags, struct sockaddr *from, socklen_t *fromlen)
{
    struct sockaddr_nl nl;
    struct iovec iov = {buf, len};
    struct msghdr m = {.msg_name = from ? &nl : NULL, .msg_namelen = sizeof nl, .msg_iov = &iov, .msg_iovlen = 1};
    ssize_t n = vc_nl_recvmsg(fd, &m, flags);
    if (n >= 0 && from && fromlen) {
        memcpy(from, &nl, *fromlen < sizeof nl ? *fromlen : sizeof nl);
        *fromlen = sizeof nl;
    }
    return n;
}
