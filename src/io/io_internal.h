/* Helpers shared by the files of src/io (not part of the public API). */
#ifndef CUPID_IO_INTERNAL_H
#define CUPID_IO_INTERNAL_H

#include <stdio.h>

/** Shortest of "%.15g" / "%.17g" that reads back to exactly @p v (finite v); buf >= 32 bytes. */
void cupid_io_format_double(double v, char *buf, size_t size);

/** Write @p s to @p out with the five XML special characters escaped (attribute-safe). */
void cupid_io_xml_escape(FILE *out, const char *s);

#endif
