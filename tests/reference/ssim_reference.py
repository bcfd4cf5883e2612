import numpy as np
from skimage.metrics import structural_similarity as ssim
W, H = 40, 30
x = np.arange(W)[None, :, None].astype(np.float64); y = np.arange(H)[:, None, None].astype(np.float64); c = np.arange(3)[None, None, :].astype(np.float64)
a = (0.5 + 0.35 * np.sin(0.21 * x + 0.9 * c) * np.cos(0.17 * y)).astype(np.float32)
b = np.clip(a.astype(np.float64) + 0.15 * np.sin(0.05 * x * y + c), 0, 1).astype(np.float32)
d = (1.0 - a.astype(np.float64)).astype(np.float32)
kw = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0)
def luma(im): im = im.astype(np.float64); return 0.2126 * im[..., 0] + 0.7152 * im[..., 1] + 0.0722 * im[..., 2]
for name, o in [('b', b), ('d', d)]:
    print(name, 'luma %.10f' % ssim(luma(a), luma(o), **kw), 'rgb %.10f' % ssim(a.astype(np.float64), o.astype(np.float64), channel_axis=2, **kw))
