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


def panels(path, title, panels, ncols=3):
    """One small plot per panel: (title, xlabel, ylabel, series, logx), series as in loglog; the
    y axis is logarithmic. Writes a PNG to path; returns False without matplotlib."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    nrows = (len(panels) + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(4 * ncols, 3.2 * nrows), squeeze=False)
    for ax, (ptitle, xlabel, ylabel, series, logx) in zip(axes.flat, panels):
        for x, y, style, label in series:
            ax.plot(x, y, style, label=label)
        ax.set_yscale("log")
        if logx:
            ax.set_xscale("log")
        ax.set_title(ptitle, fontsize=10)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        if any(label for *_, label in series):
            ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    print(f"\nplot: {path}")
    return True
