"""Model files: resolving a name or path, checking a file before anything is built from it, loading motion
models, latent models and evaluators, and writing releases with their checksums."""
