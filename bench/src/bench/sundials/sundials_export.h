/* sundials_export.h for SUNDIALS 7.1.1, written by hand for `cargo xtask bench`
 * (bench/src/bench/sundials_build.rs) in place of the one CMake's GenerateExportHeader writes
 * for a shared library built with gcc: the API is exported with default visibility. */
#ifndef SUNDIALS_EXPORT_H
#define SUNDIALS_EXPORT_H

#define SUNDIALS_EXPORT __attribute__((visibility("default")))
#define SUNDIALS_NO_EXPORT __attribute__((visibility("hidden")))
#define SUNDIALS_DEPRECATED __attribute__((__deprecated__))
#define SUNDIALS_DEPRECATED_EXPORT SUNDIALS_EXPORT SUNDIALS_DEPRECATED
#define SUNDIALS_DEPRECATED_NO_EXPORT SUNDIALS_NO_EXPORT SUNDIALS_DEPRECATED

#endif /* SUNDIALS_EXPORT_H */
