/*
 * gearsim/version.h - the version of gearsim: the one place it is written.
 *
 * CMake's project(), the pkg-config file, the Python package and the FMUs
 * read it from here; tests check that the built library (gs_version()) and
 * every consumer agree.
 */
#ifndef GEARSIM_VERSION_H
#define GEARSIM_VERSION_H

#define GS_VERSION_MAJOR  0
#define GS_VERSION_MINOR  1
#define GS_VERSION_PATCH  0
#define GS_VERSION_STRING "0.1.0"

#endif /* GEARSIM_VERSION_H */
