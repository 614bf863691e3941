"""What every command runs on: the user-error type, paths, atomic files, safe file reading, run provenance,
the error boundary of the entry points and this machine's hardware."""
