#define _POSIX_C_SOURCE 200809L
#include "daemon/service.h"

#include <stdarg.h>
#include <stdio.h>

#include "config.h"
#ifdef HAVE_LIBSYSTEMD
#include <systemd/sd-daemon.h>
#endif

void service_ready(void)
{
#ifdef HAVE_LIBSYSTEMD
    sd_notify(0, "READY=1\nSTATUS=idle");
#endif
}

void service_status(const char *fmt, ...)
{
#ifdef HAVE_LIBSYSTEMD
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    sd_notifyf(0, "STATUS=%s", msg);
#else
    (void)fmt;
#endif
}

void service_stopping(void)
{
#ifdef HAVE_LIBSYSTEMD
    sd_notify(0, "STOPPING=1\nSTATUS=stopping");
#endif
}
