/*
 * What the preload library's C files share: the interface files ($DIR/if/<name>, preload_links.c) and the
 * rtnetlink emulation (preload_netlink.c) that preload.c's intercepted calls hand NETLINK_ROUTE sockets to.
 */
#ifndef VCAN_PRELOAD_H
#define VCAN_PRELOAD_H
#include <net/if.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <sys/uio.h>

#define ENV_DIR "ENCODER_CONFORMANCE_VCAN_DIR"
#define MAX_FDS 65536
#define VC_DEFAULT_TXQLEN 1000 /* a vcan's qlen: tx_queue_len 0 becomes IFF_NO_QUEUE with the default 1000 */

/* an interface of the bus: $DIR/if/<name> holds "<ifindex> <mtu> <vcan|wire> <up 0|1> <txqlen>" */
struct vc_link {
    char name[IF_NAMESIZE];
    int ifindex, mtu, wire, up;
    unsigned int txqlen;
};

/* the next definition of a function this library intercepts (glibc's) */
void *vc_real(const char *name);
const char *vc_hub_dir(void);
int vc_in_owner(void); /* 0 in a vfork() child, which shares the parent's memory */

/* preload_links.c */
int vc_valid_name(const char *name);
int vc_link_by_name(const char *name, struct vc_link *link);
int vc_link_by_index(int ifindex, struct vc_link *link);
int vc_link_list(struct vc_link *links, int max); /* by ifindex; how many */
int vc_links_lock(void);                          /* the directory's lock (an fd), -1 if none */
void vc_links_unlock(int lock);
int vc_link_store(const struct vc_link *link); /* with the lock held; 0 or -1 with errno */
int vc_hub_alive(void);                        /* a hub serves the directory: the interfaces have a carrier */

/* preload_netlink.c: socket() returns -2 when the socket is not one it emulates */
int vc_nl_socket(int domain, int type, int protocol);
int vc_nl_owns(int fd);
void vc_nl_forget(int fd);
void vc_nl_dup(int fd, int newfd); /* newfd now names what fd names */
int vc_nl_bind(int fd, const struct sockaddr *addr, socklen_t len);
int vc_nl_connect(int fd, const struct sockaddr *addr, socklen_t len);
int vc_nl_getsockname(int fd, struct sockaddr *addr, socklen_t *len);
int vc_nl_setsockopt(int fd, int level, int opt, const void *val, socklen_t len);
int vc_nl_getsockopt(int fd, int level, int opt, void *val, socklen_t *len);
ssize_t vc_nl_send(int fd, const struct iovec *iov, size_t iovcnt);
ssize_t vc_nl_recvmsg(int fd, struct msghdr *msg, int flags);
ssize_t vc_nl_recvfrom(int fd, void *buf, size_t len, int flags, struct sockaddr *from, socklen_t *fromlen);
#endif
