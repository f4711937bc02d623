#ifndef SHADEBENCH_AXIS_H
#define SHADEBENCH_AXIS_H

/* A chart axis's round tick step, shared by the daemon's charts
 * (daemon/reports/charts.c) and the client's trend chart (client/trend.c),
 * so that both draw the same ticks. Pure; any thread. */

/* The step, 1, 2 or 5 times a power of ten, that cuts span into about six
 * ticks. span > 0. */
double axis_tick_step(double span);

#endif
