"""Figures of chuteflow (matplotlib); each module draws one kind of figure from saved results."""
