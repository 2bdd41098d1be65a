/* freeport N: prints N distinct TCP ports that are free now, one a line, for a test that starts
 * servers of its own (tests/farm/slurm.sh). Each is proved free by binding it on every IPv4
 * address (without SO_REUSEADDR, so a port still in TIME_WAIT counts as taken), and each lies
 * outside the kernel's ephemeral range (net.ipv4.ip_local_port_range), so no outgoing
 * connection is handed it before the server binds it. The search starts at a point drawn from
 * the process id and the clock, so two tests started together rarely probe the same ports.
 * Exit 1 when fewer than N are free, 2 on bad usage. */
#include <errno.h>
#include <netinet/in.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define LOWEST 10000 /* clear of the well-known and registered services most hosts run */
#define MAX_PORTS 16

/* The ephemeral range, or Linux's default where it cannot be read. */
static void ephemeral_range(long *lo, long *hi)
{
    *lo = 32768;
    *hi = 60999;
    FILE *f = fopen("/proc/sys/net/ipv4/ip_local_port_range", "r");
    if (!f)
        return;
    long a, b;
    if (fscanf(f, "%ld %ld", &a, &b) == 2 && a > 0 && b >= a) {
        *lo = a;
        *hi = b;
    }
    fclose(f);
}

/* A socket bound to port on every IPv4 address, or -1 when the port is taken. */
static int bind_port(long port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0)
        return -1;
    struct sockaddr_in a;
    memset(&a, 0, sizeof(a));
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_ANY);
    a.sin_port = htons((uint16_t)port);
    if (bind(fd, (struct sockaddr *)&a, sizeof(a)) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

int main(int argc, char **argv)
{
    char *end = NULL;
    long n = argc == 2 ? strtol(argv[1], &end, 10) : 0;
    if (argc != 2 || *end || n < 1 || n > MAX_PORTS) {
        fprintf(stderr, "usage: freeport N (1..%d)\n", MAX_PORTS);
        return 2;
    }
    long lo, hi;
    ephemeral_range(&lo, &hi);
    /* The candidates, LOWEST..65535 less the ephemeral range, counted from 0. */
    long below = lo > LOWEST ? lo - LOWEST : 0, above = hi < 65535 ? 65535 - hi : 0;
    long count = below + above;
    if (count < n) {
        fprintf(stderr, "freeport: no ports outside the ephemeral range %ld-%ld\n", lo, hi);
        return 1;
    }
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    long start = (long)(((unsigned long)getpid() * 2654435761u + (unsigned long)ts.tv_nsec) %
                        (unsigned long)count);
    int fds[MAX_PORTS];
    long ports[MAX_PORTS], found = 0;
    for (long k = 0; k < count && found < n; k++) {
        long i = (start + k) % count, port = i < below ? LOWEST + i : hi + 1 + (i - below);
        int fd = bind_port(port);
        if (fd < 0)
            continue;
        fds[found] = fd; /* held until all are found, so they differ */
        ports[found++] = port;
    }
    for (long i = 0; i < found; i++)
        close(fds[i]);
    if (found < n) {
        fprintf(stderr, "freeport: only %ld of %ld ports are free\n", found, n);
        return 1;
    }
    for (long i = 0; i < found; i++)
        printf("%ld\n", ports[i]);
    return 0;
}
