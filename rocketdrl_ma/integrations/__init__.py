"""Faces for third-party training libraries. Each imports its library only when used: the base install has none."""
