#ifndef SHADEBENCH_LOG_H
#define SHADEBENCH_LOG_H

enum log_level { LOG_DEBUG, LOG_INFO, LOG_WARN, LOG_ERROR };

/* Messages below this level are dropped; set once at start-up. */
void log_set_level(enum log_level level);
enum log_level log_get_level(void);

void log_write(enum log_level level, const char *file, int line,
               const char *fmt, ...) __attribute__((format(printf, 4, 5)));

#define LOG(level, ...) log_write((level), __FILE__, __LINE__, __VA_ARGS__)

#endif
