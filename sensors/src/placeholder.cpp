namespace kestrel {}
