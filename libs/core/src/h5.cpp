// implemented by the core I/O work
