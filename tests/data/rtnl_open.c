/*
 * Opens a CAN interface the way libsocketcan and C/C++ CANopen stacks do: if_nametoindex, then rtnetlink
 * (RTM_GETLINK for that index: name, type, MTU, transmit queue length, state, kind), a dump of every link,
 * an unknown index (the kernel's ENODEV), then a CAN_RAW socket bound to it. One "key=value ..." line per
 * answer on stdout, for tests/test_vcan_netlink.py. Usage: rtnl_open IFNAME
 */
#include <errno.h>
#include <linux/can.h>
#include <linux/if_link.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

static char buf[65536];

static int ask(int fd, int type, int flags, int ifindex, unsigned seq)
{
    struct { struct nlmsghdr n; struct ifinfomsg i; } req;
    struct sockaddr_nl kernel = {.nl_family = AF_NETLINK};
    memset(&req, 0, sizeof req);
    req.n.nlmsg_len = NLMSG_LENGTH(sizeof req.i), req.n.nlmsg_type = (unsigned short)type;
    req.n.nlmsg_flags = (unsigned short)(NLM_F_REQUEST | flags), req.n.nlmsg_seq = seq;
    req.i.ifi_family = AF_UNSPEC, req.i.ifi_index = ifindex;
    return sendto(fd, &req, req.n.nlmsg_len, 0, (struct sockaddr *)&kernel, sizeof kernel) == req.n.nlmsg_len;
}

static void print_link(const char *what, struct nlmsghdr *h)
{
    struct ifinfomsg *ifi = NLMSG_DATA(h);
    int left = (int)IFLA_PAYLOAD(h);
    char name[IF_NAMESIZE] = "", kind[32] = "";
    unsigned mtu = 0, txqlen = 0, oper = 255;
    for (struct rtattr *a = IFLA_RTA(ifi); RTA_OK(a, left); a = RTA_NEXT(a, left)) {
        if (a->rta_type == IFLA_IFNAME)
            snprintf(name, sizeof name, "%s", (char *)RTA_DATA(a));
        else if (a->rta_type == IFLA_MTU)
            memcpy(&mtu, RTA_DATA(a), 4);
        else if (a->rta_type == IFLA_TXQLEN)
            memcpy(&txqlen, RTA_DATA(a), 4);
        else if (a->rta_type == IFLA_OPERSTATE)
            oper = *(unsigned char *)RTA_DATA(a);
        else if (a->rta_type == IFLA_LINKINFO) {
            int n = (int)RTA_PAYLOAD(a);
            for (struct rtattr *i = RTA_DATA(a); RTA_OK(i, n); i = RTA_NEXT(i, n))
                if (i->rta_type == IFLA_INFO_KIND)
                    snprintf(kind, sizeof kind, "%s", (char *)RTA_DATA(i));
        }
    }
    printf("%s name=%s index=%d type=%u flags=%#x mtu=%u txqlen=%u operstate=%u kind=%s\n", what, name,
           ifi->ifi_index, ifi->ifi_type, ifi->ifi_flags, mtu, txqlen, oper, kind);
}

/* reads answers to seq until one that ends it (an answer, an error or NLMSG_DONE); 0 if none came */
static int answers(int fd, unsigned seq, const char *what, unsigned portid)
{
    for (;;) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 5000) != 1)
            return 0;
        struct sockaddr_nl from;
        struct iovec iov = {buf, sizeof buf};
        struct msghdr m = {.msg_name = &from, .msg_namelen = sizeof from, .msg_iov = &iov, .msg_iovlen = 1};
        int len = (int)recvmsg(fd, &m, 0), more = 0;
        if (len <= 0 || m.msg_namelen != sizeof from || from.nl_family != AF_NETLINK || from.nl_pid != 0)
            return printf("bad-answer len=%d namelen=%u\n", len, m.msg_namelen), 0;
        for (struct nlmsghdr *h = (struct nlmsghdr *)buf; NLMSG_OK(h, len); h = NLMSG_NEXT(h, len)) {
            if (h->nlmsg_seq != seq || h->nlmsg_pid != portid)
                return printf("bad-answer seq=%u pid=%u\n", h->nlmsg_seq, h->nlmsg_pid), 0;
            if (h->nlmsg_type == NLMSG_DONE)
                return printf("done\n"), 1;
            if (h->nlmsg_type == NLMSG_ERROR)
                return printf("error=%d\n", ((struct nlmsgerr *)NLMSG_DATA(h))->error), 1;
            if (h->nlmsg_type == RTM_NEWLINK)
                print_link(what, h);
            more |= (h->nlmsg_flags & NLM_F_MULTI) != 0;
        }
        if (!more)
            return 1;
    }
}

int main(int argc, char **argv)
{
    if (argc != 2)
        return 2;
    unsigned ifindex = if_nametoindex(argv[1]);
    printf("nametoindex=%u\n", ifindex);
    int fd = socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
    struct sockaddr_nl local = {.nl_family = AF_NETLINK};
    socklen_t len = sizeof local;
    if (fd < 0 || bind(fd, (struct sockaddr *)&local, sizeof local) < 0 ||
        getsockname(fd, (struct sockaddr *)&local, &len) < 0)
        return printf("netlink-failed errno=%d %s\n", errno, strerror(errno)), 1;
    printf("bound family=%d portid-set=%d\n", local.nl_family, local.nl_pid != 0);
    if (ask(fd, RTM_GETLINK, 0, (int)ifindex, 1))
        answers(fd, 1, "link", local.nl_pid);
    if (ask(fd, RTM_GETLINK, NLM_F_DUMP, 0, 2))
        answers(fd, 2, "dump", local.nl_pid);
    if (ask(fd, RTM_GETLINK, NLM_F_ACK, 999999, 3))
        answers(fd, 3, "unknown", local.nl_pid);
    struct pollfd p = {fd, POLLIN, 0};
    printf("left-over=%d\n", poll(&p, 1, 0));
    close(fd);
    int can = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    struct sockaddr_can addr = {.can_family = AF_CAN, .can_ifindex = (int)ifindex};
    printf("can-bind=%d\n", can >= 0 ? bind(can, (struct sockaddr *)&addr, sizeof addr) : -1);
    return 0;
}
