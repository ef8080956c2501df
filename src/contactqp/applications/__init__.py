"""Applications built on the library: the spring chain, the rod over an obstacle, riveting of
plates (with or without friction), sliding soil layers and rough surfaces."""
