"""Log-log plots for the benchmarks (matplotlib, Agg backend; skipped when it is missing)."""


def loglog(path, title, xlabel, series, ylabel="time [s]"):
    """series: list of (x, y, style, label). Writes a PNG to path; returns False without matplotlib."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, ax = plt.subplots(figsize=(6, 4))
    for x, y, style, label in series:
        ax.loglog(x, y, style, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"\nplot: {path}")
    return True
