"""oif: the object-in-fluid cell model (placeholder until the OIF issue)."""
