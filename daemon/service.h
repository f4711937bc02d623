#ifndef SHADEBENCH_SERVICE_H
#define SHADEBENCH_SERVICE_H

/* Tells the service manager how the daemon is doing (sd_notify): READY=1
 * once the GL context is up and the API listens, STATUS= with the running
 * job. No-ops when not run by systemd or built without libsystemd. */
void service_ready(void);
void service_status(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
void service_stopping(void);

#endif
